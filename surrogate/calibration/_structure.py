"""Is what remains after the chosen effects noise? Tests of structure within curves.

Each curve's residuals first lose the part a specimen-to-specimen change of A or tau
explains (projection on the curve's own d angle/d log A and d angle/d log tau): replicate
scatter of that kind is noise, not a missing effect. On what is left:

* lag-1 autocorrelation, pooled over curves in time (or pressure) order, against its exact
  expectation for white noise after that projection, -sum tr(D H) / sum (n - 2);
* the Wald-Wolfowitz runs test on the residual signs, summed over curves.

Structured when z(lag-1) > 3 or z(runs) < -3 (too few sign changes).
"""

from __future__ import annotations

import numpy as np

Z_LIMIT = 3.0


def structure_test(curve: np.ndarray, residual: np.ndarray, nuisance: np.ndarray
                   ) -> dict[str, float | bool]:
    """``curve`` (n,) curve index of each row in order; ``nuisance`` (n, m) columns that
    replicate scatter may explain per curve. Returns the statistics and ``structured``."""
    num = den = expected_num = expected_den = 0.0
    pairs = 0
    runs = runs_mean = runs_var = 0.0
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        n = rows.size
        e = residual[rows]
        X = nuisance[rows]
        X = X[:, np.linalg.norm(X, axis=0) > 1e-12]
        if X.size and n > X.shape[1] + 1:
            Q, _ = np.linalg.qr(X)
            H = Q @ Q.T
            e = e - H @ e
            rank = Q.shape[1]
        else:
            H = np.zeros((n, n))
            rank = 0
        num += float(e[:-1] @ e[1:])
        den += float(e @ e)
        expected_num += -float(np.trace(H, offset=1))  # tr(D H), D = lag-1 pairs
        expected_den += n - rank
        pairs += n - 1
        s = np.sign(e[np.abs(e) > 1e-12])
        n1, n2 = float(np.sum(s > 0)), float(np.sum(s < 0))
        if n1 and n2:
            runs += 1 + float(np.sum(s[1:] != s[:-1]))
            m = n1 + n2
            runs_mean += 1 + 2 * n1 * n2 / m
            runs_var += 2 * n1 * n2 * (2 * n1 * n2 - m) / (m * m * (m - 1))
    r1 = num / den if den > 0 else 0.0
    r1_expected = expected_num / expected_den if expected_den > 0 else 0.0
    z_lag1 = (r1 - r1_expected) * np.sqrt(max(pairs, 1))
    z_runs = (runs - runs_mean) / np.sqrt(runs_var) if runs_var > 0 else 0.0
    return {"lag1_autocorrelation": float(r1), "lag1_expected_if_noise": float(r1_expected),
            "z_lag1": float(z_lag1), "runs": float(runs), "runs_expected_if_noise":
            float(runs_mean), "z_runs": float(z_runs),
            "structured": bool(z_lag1 > Z_LIMIT or z_runs < -Z_LIMIT)}
