"""Least squares of an augmented model, its clustered standard errors, BIC, and the
cross-validation by curve.

Standard errors are the sandwich estimator clustered by curve (specimen-to-specimen
scatter is shared along a curve, so it counts in full); BIC = n ln(SSE/n) + k ln n.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from surrogate.calibration._data import Observations
from surrogate.calibration._model import AugmentedModel

# Residuals are capped while fitting: a trial step where the baseline has no answer (past
# the FE range: NaN) stays a large finite penalty with a finite Jacobian.
R_CAP_DEG = 1e3


@dataclass
class FitResult:
    """A fitted augmented model and the statistics of the fit."""

    model: AugmentedModel
    x: np.ndarray
    sse: float
    n: int
    cov: np.ndarray
    success: bool
    residual: np.ndarray = field(repr=False)
    jac: np.ndarray | None = field(default=None, repr=False)
    #: each parameter's sd from the baseline's own error at the fitted design, coherent
    #: within a design (_backing.py; zero without a physical effect), and that error's
    #: sd, RMS over the readings
    baseline_shift: np.ndarray | None = field(default=None, repr=False)
    baseline_sd_deg: float | None = None

    @property
    def k(self) -> int:
        return self.model.layout.k

    @property
    def effects(self) -> tuple[str, ...]:
        return tuple(e.id for e in self.model.effects)

    @property
    def bic(self) -> float:
        return self.n * float(np.log(max(self.sse, 1e-300) / self.n)) + self.k * np.log(self.n)

    @property
    def rms_deg(self) -> float:
        return float(np.sqrt(self.sse / self.n))

    @property
    def values(self) -> dict[str, float]:
        """The effects' parameters by name (physical units)."""
        return self.model.values(self.x)

    def sd(self) -> dict[str, float]:
        """Standard errors: the data's, and the baseline's own uncertainty at a fitted
        physical change when ``baseline_shift`` is set (_backing.py)."""
        s = np.sqrt(np.clip(np.diag(self.cov), 0.0, np.inf))
        return dict(zip(self.model.layout.names, s.tolist(), strict=True))

    def sd_baseline(self) -> dict[str, float]:
        """The baseline's part of each standard error (0 without a physical effect)."""
        d = np.zeros(self.k) if self.baseline_shift is None else np.abs(self.baseline_shift)
        return dict(zip(self.model.layout.names, d.tolist(), strict=True))

    def angles(self) -> np.ndarray:
        return self.model.angles(self.x)

    def conditional_sd(self, name: str, given: tuple[str, ...]) -> float:
        """Standard error of ``name`` with the parameters ``given`` held at their fitted
        values (a shape parameter such as a retardation time is undefined when its effect
        is off, so its trade-off with the size must not dilute the test of the size)."""
        names = list(self.model.layout.names)
        idx = [names.index(name)] + [names.index(g) for g in given]
        sub = self.cov[np.ix_(idx, idx)]
        try:
            precision = np.linalg.inv(sub)
        except np.linalg.LinAlgError:
            return float(np.sqrt(max(sub[0, 0], 0.0)))
        return float(1.0 / np.sqrt(precision[0, 0])) if precision[0, 0] > 0 else np.inf


def _residual_fn(model: AugmentedModel) -> Callable[[np.ndarray], np.ndarray]:
    y = model.obs.angle_deg

    def residual(x: np.ndarray) -> np.ndarray:
        r = model.angles(x) - y
        return np.clip(np.nan_to_num(r, nan=R_CAP_DEG), -R_CAP_DEG, R_CAP_DEG)

    return residual


def fit(model: AugmentedModel, x0: np.ndarray | None = None) -> FitResult:
    lay = model.layout
    residual = _residual_fn(model)
    if lay.k == 0:
        r = residual(np.zeros(0))
        return FitResult(model, np.zeros(0), float(r @ r), r.size, np.zeros((0, 0)), True, r)
    start = lay.start if x0 is None else x0
    start = np.clip(start, lay.lower, lay.upper)
    res = least_squares(residual, start, bounds=(lay.lower, lay.upper), x_scale="jac",
                        method="trf", diff_step=1e-4, max_nfev=60 * max(lay.k, 1))
    r = res.fun
    cov = cluster_covariance(res.jac, r, model.obs.curve)
    return FitResult(model, res.x, float(r @ r), r.size, cov, bool(res.success), r, res.jac)


def cluster_covariance(jac: np.ndarray, r: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """(J'J)^-1 [sum_c (J_c' r_c)(J_c' r_c)'] (J'J)^-1 x G/(G-1): covariance of the fitted
    parameters robust to scatter shared within a curve."""
    bread = np.linalg.pinv(jac.T @ jac)
    g = np.zeros((int(curve.max()) + 1, jac.shape[1]))
    np.add.at(g, curve, jac * r[:, None])
    n_groups = g.shape[0]
    meat = g.T @ g * n_groups / max(n_groups - 1, 1)
    return bread @ meat @ bread


def curve_folds(n_curves: int, k: int = 5) -> list[np.ndarray]:
    """Grouped K-fold by curve: curve i is held out in fold i mod K (replicates, usually
    listed together, land in different folds); K is reduced to ``n_curves``."""
    if n_curves < 2 or k < 2:
        raise ValueError(f"cross-validation by curve needs >= 2 curves and folds, got "
                         f"{n_curves} curves, {k} folds (check_calibratable says so first)")
    k = min(k, n_curves)
    return [np.arange(i, n_curves, k) for i in range(k)]


def cross_validate(obs: Observations, make: Callable[[Observations], AugmentedModel],
                   full: FitResult, k: int = 5) -> tuple[float, np.ndarray]:
    """RMS error (deg) of predicting each held-out curve from a fit that did not see it,
    and the per-row out-of-fold residual. A family absent from a training set keeps its
    open scales at 1 (the baseline as is)."""
    resid = np.empty(obs.n)
    for held in curve_folds(obs.n_curves, k):
        train = obs.subset(np.setdiff1d(np.arange(obs.n_curves), held))
        test = obs.subset(held)
        m_train = make(train)
        f = fit(m_train, _transfer(full, m_train))
        m_test = make(test)
        x = _transfer(f, m_test)
        rows = np.isin(obs.curve, held)
        resid[rows] = m_test.angles(x) - test.angle_deg
    if not np.all(np.isfinite(resid)):  # a held-out curve past the baseline's range
        return float("inf"), np.where(np.isfinite(resid), resid, np.nan)
    return float(np.sqrt(np.mean(resid**2))), resid


def _transfer(f: FitResult, target: AugmentedModel) -> np.ndarray:
    """The fitted numbers of ``f`` in ``target``'s layout (by name; absent -> start)."""
    by_name = dict(zip(f.model.layout.names, f.x.tolist(), strict=True))
    lay = target.layout
    x = np.array([by_name.get(n, s) for n, s in zip(lay.names, lay.start, strict=True)])
    return x if lay.k else np.zeros(0)


def paired_cv(resid_a: np.ndarray, resid_b: np.ndarray, curve: np.ndarray) -> float:
    """How decisively held-out curves tell set A from set B: z of the mean difference of
    squared out-of-fold errors, A - B, with curves as the independent units (a specimen's
    scatter is shared along its curve). Negative: A predicts unseen curves better."""
    ok = np.isfinite(resid_a) & np.isfinite(resid_b)
    if not np.any(ok):
        return float("nan")
    d = np.zeros(int(curve.max()) + 1)
    np.add.at(d, curve[ok], resid_a[ok] ** 2 - resid_b[ok] ** 2)
    used = np.unique(curve[ok])
    d = d[used] / ok.sum() * used.size  # each curve's share of the mean difference
    if used.size < 3:
        return float("nan")
    se = float(d.std(ddof=1) / np.sqrt(used.size))
    mean = float(d.mean())
    return mean / se if se > 0 else (0.0 if mean == 0 else float(np.sign(mean) * np.inf))
