"""Per-curve fits of angle = A (exp(p / tau) - 1), as in the paper's Tables 4 and 5.

Three fits per curve: free (A and tau), tau fixed (A only) and A fixed (tau only); each
returns the estimates, their standard errors (sqrt of the diagonal of
s^2 (J^T J)^-1, s^2 = RSS / (n - k)) and R^2 = 1 - RSS / TSS. Then the paper's second
stage: the length constant a from A against L (a line through the origin) and (a_t, b_t)
from tau against t, tau = a_t log10(b_t t) (a straight line in log10 t).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from surrogate.exponential.equations import angle_from_constants


@dataclass(frozen=True)
class CurveFit:
    """One curve's fit: A_deg, tau_pa and their standard errors (None when fixed or
    undetermined), R^2, number of points, and which parameter was fixed (or "")."""

    A_deg: float
    tau_pa: float
    A_se: float | None
    tau_se: float | None
    r2: float
    n_points: int
    fixed: str = ""

    def as_dict(self) -> dict[str, object]:
        return {"A_deg": self.A_deg, "tau_pa": self.tau_pa, "A_se": self.A_se,
                "tau_se": self.tau_se, "r2": self.r2, "n_points": self.n_points,
                "fixed": self.fixed}


def _r2(y: np.ndarray, resid: np.ndarray) -> float:
    tss = float(np.sum((y - y.mean()) ** 2))
    return 1.0 - float(np.sum(resid ** 2)) / tss if tss > 0 else float("nan")


def _se(jac: np.ndarray, resid: np.ndarray) -> list[float | None]:
    n, k = jac.shape
    if n <= k:
        return [None] * k
    s2 = float(resid @ resid) / (n - k)
    try:
        cov = np.linalg.inv(jac.T @ jac) * s2
    except np.linalg.LinAlgError:
        return [None] * k
    return [math.sqrt(v) if v >= 0 else None for v in np.diag(cov)]


def fit_tau_fixed(p: np.ndarray, y: np.ndarray, tau_pa: float) -> CurveFit:
    """A by linear least squares with tau fixed."""
    g = angle_from_constants(1.0, tau_pa, p)
    A = float(g @ y / (g @ g))
    resid = y - A * g
    return CurveFit(A, tau_pa, _se(g[:, None], resid)[0], None, _r2(y, resid), len(p), "tau")


def fit_A_fixed(p: np.ndarray, y: np.ndarray, A_deg: float) -> CurveFit:
    """tau by nonlinear least squares with A fixed (A and the data share a sign)."""
    tau0 = _tau_grid_start(p, y, A_deg)

    def res(q: np.ndarray) -> np.ndarray:
        return angle_from_constants(A_deg, q[0], p) - y

    sol = least_squares(res, [tau0], bounds=([1e-9 * p.max()], [np.inf]), x_scale=[tau0])
    tau = float(sol.x[0])
    resid = -sol.fun
    return CurveFit(A_deg, tau, None, _se(sol.jac, resid)[0], _r2(y, resid), len(p), "A")


def fit_free(p: np.ndarray, y: np.ndarray) -> CurveFit:
    """A and tau together; started from the best of a grid of tau values."""
    best = None
    for tau in p.max() * np.geomspace(0.03, 30.0, 40):
        f = fit_tau_fixed(p, y, float(tau))
        if best is None or f.r2 > best.r2:
            best = f
    assert best is not None

    def res(q: np.ndarray) -> np.ndarray:
        return angle_from_constants(q[0], q[1], p) - y

    x0 = [best.A_deg, best.tau_pa]
    sol = least_squares(res, x0, bounds=([-np.inf, 1e-6 * p.max()], [np.inf, np.inf]),
                        x_scale=[abs(best.A_deg) or 1.0, best.tau_pa])
    resid = -sol.fun
    se = _se(sol.jac, resid)
    return CurveFit(float(sol.x[0]), float(sol.x[1]), se[0], se[1], _r2(y, resid), len(p), "")


def _tau_grid_start(p: np.ndarray, y: np.ndarray, A: float) -> float:
    taus = p.max() * np.geomspace(0.03, 30.0, 60)
    sse = [float(np.sum((angle_from_constants(A, tau, p) - y) ** 2)) for tau in taus]
    return float(taus[int(np.argmin(sse))])


@dataclass(frozen=True)
class LineFit:
    """A straight-line fit: parameter values, standard errors (None if undetermined), R^2."""

    names: tuple[str, ...]
    values: tuple[float, ...]
    se: tuple[float | None, ...]
    r2: float
    n_points: int

    def as_dict(self) -> dict[str, object]:
        out: dict[str, object] = {n: v for n, v in zip(self.names, self.values, strict=True)}
        out.update({f"{n}_se": s for n, s in zip(self.names, self.se, strict=True)})
        out.update(r2=self.r2, n_points=self.n_points)
        return out


def length_constant(L_mm: np.ndarray, A_deg: np.ndarray) -> LineFit:
    """a (deg/mm) of A = a L, a line through the origin; R^2 against the mean of A."""
    L, A = np.asarray(L_mm, float), np.asarray(A_deg, float)
    a = float(L @ A / (L @ L))
    resid = A - a * L
    se = _se(L[:, None], resid)[0]
    return LineFit(("a_deg_per_mm",), (a,), (se,), _r2(A, resid) if len(A) > 1 else float("nan"),
                   len(L))


def thickness_constants(t_mm: np.ndarray, tau: np.ndarray) -> LineFit:
    """(a_t, b_t) of tau = a_t log10(b_t t) = a_t log10 t + a_t log10 b_t, by linear least
    squares in log10 t; standard errors by the delta method (None with < 3 points)."""
    x, y = np.log10(np.asarray(t_mm, float)), np.asarray(tau, float)
    X = np.column_stack([x, np.ones_like(x)])
    (slope, icept), *_ = np.linalg.lstsq(X, y, rcond=None)
    resid = y - X @ [slope, icept]
    with np.errstate(over="ignore", divide="ignore"):  # tau flat in t: b_t = inf, said so
        b_t = float(np.float64(10.0) ** (icept / slope)) if slope != 0 else math.inf
    n = len(x)
    if n > 2:
        cov = np.linalg.inv(X.T @ X) * float(resid @ resid) / (n - 2)
        # b_t = 10^(i/s): d b_t / d s = -b_t ln10 i / s^2, d b_t / d i = b_t ln10 / s
        g = np.array([-b_t * math.log(10) * icept / slope**2, b_t * math.log(10) / slope])
        with np.errstate(over="ignore", invalid="ignore"):  # b_t ~ 1e200: tau flat in t
            se: tuple[float | None, ...] = (math.sqrt(cov[0, 0]),
                                            math.sqrt(float(g @ cov @ g)))
    else:
        se = (None, None)
    return LineFit(("a_t_pa", "b_t_per_mm"), (float(slope), float(b_t)), se, _r2(y, resid), n)
