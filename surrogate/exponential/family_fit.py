"""Joint fit of one family's curves: (a, a_t, b_t) [and c for the extended form] at once.

Least squares on every usable point of every curve (scipy.optimize.least_squares),
weighted by the residual-scatter model of ``surrogate.exponential.bands`` (two passes: unweighted,
then weighted with the scatter estimated from the first pass). The fit runs in the fit
coordinates of ``surrogate.exponential.equations`` (log10 b_t in place of b_t), and the
covariance is taken there: (J_w^T J_w)^-1 times the weighted residual variance RSS_w / (n - k), J_w
the weighted Jacobian at the solution (columns scaled to unit norm before the
pseudo-inverse). With fewer than two membrane thicknesses b_t is not identifiable and
is held at the paper's value (its variance is then zero).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from surrogate.exponential import bands, equations
from surrogate.exponential.paper_tables import B_T_PER_MM
from surrogate.exponential.parameters import ModelParameters
from surrogate.exponential.per_curve_fits import fit_free, thickness_constants

LOG10_B_T_MAX = 100.0  # upper bound of log10 b_t (1/mm) in the fit: tau flat in t


@dataclass(frozen=True)
class Points:
    """A family's data flattened: per point L_mm, t_mm, pressure_pa, value (deg or mN)
    and the index of the curve (design) it came from."""

    L_mm: np.ndarray
    t_mm: np.ndarray
    pressure_pa: np.ndarray
    value: np.ndarray
    curve: np.ndarray

    def subset(self, mask: np.ndarray) -> Points:
        return Points(self.L_mm[mask], self.t_mm[mask], self.pressure_pa[mask],
                      self.value[mask], self.curve[mask])

    @property
    def n_curves(self) -> int:
        return len(np.unique(self.curve))


def make_points(curves: list[tuple[float, float, np.ndarray, np.ndarray]]) -> Points:
    """From [(L_mm, t_mm, pressure_pa, value), ...]."""
    parts = [(np.full(len(p), L), np.full(len(p), t), p, y, np.full(len(p), i))
             for i, (L, t, p, y) in enumerate(curves)]
    cols = [np.concatenate([part[j] for part in parts]) if parts else np.empty(0)
            for j in range(5)]
    L, t, p, y = (c.astype(float) for c in cols[:4])
    return Points(L, t, p, y, cols[4].astype(int))


def start_values(pts: Points) -> np.ndarray:
    """(a, a_t, b_t) from per-curve free fits, as the paper's two-stage procedure."""
    A, tau, L, t = [], [], [], []
    for i in np.unique(pts.curve):
        sub = pts.subset(pts.curve == i)
        f = fit_free(sub.pressure_pa, sub.value)
        A.append(f.A_deg)
        tau.append(f.tau_pa)
        L.append(sub.L_mm[0])
        t.append(sub.t_mm[0])
    L_, A_ = np.array(L), np.array(A)
    a = float(L_ @ A_ / (L_ @ L_))
    t_, tau_ = np.array(t), np.array(tau)
    if len(np.unique(t_)) >= 2:
        line = thickness_constants(t_, tau_)
        a_t, b_t = line.values
        if a_t > 0 and math.isfinite(b_t) and b_t * t_.min() > 1.0:
            return np.array([a, a_t, b_t])
    b_t = _default_b_t(t_)
    a_t = float(np.mean(tau_ / np.log10(b_t * t_)))
    return np.array([a, a_t, b_t])


def _default_b_t(t_mm: np.ndarray) -> float:
    b_t = B_T_PER_MM
    return b_t if b_t * t_mm.min() > 1.05 else 2.0 / float(t_mm.min())


def joint_fit(pts: Points, form: str = "exponential", start: np.ndarray | None = None,
              weighted: bool = True) -> ModelParameters:
    """Fit ``form`` to all points of a family; see the module docstring."""
    names = equations.PARAMETER_NAMES[form]
    theta0 = np.array(start if start is not None else start_values(pts), dtype=float)
    if form == "extended" and len(theta0) == 3:
        theta0 = np.append(theta0, 0.0)
    free = np.ones(len(names), dtype=bool)
    if len(np.unique(pts.t_mm)) < 2:
        free[equations.B_T] = False
    # fit coordinates (log10 b_t); b_t t > 1 for every t, b_t <= 1e100 /mm (tau flat in t)
    lo = np.array([-np.inf, 1e-9, -math.log10(pts.t_mm.min()) + 1e-6, -5.0])[: len(names)]
    hi = np.array([np.inf, np.inf, LOG10_B_T_MAX, 5.0])[: len(names)]
    q0 = np.clip(equations.to_fit(theta0), lo + 1e-9, hi - 1e-9)

    def solve(q_start: np.ndarray, w: np.ndarray) -> np.ndarray:
        def full(x: np.ndarray) -> np.ndarray:
            q = q_start.copy()
            q[free] = x
            return equations.from_fit(q)

        def fun(x: np.ndarray) -> np.ndarray:
            with np.errstate(over="ignore", invalid="ignore"):
                r = (equations.angle_deg(full(x), pts.L_mm, pts.t_mm, pts.pressure_pa)
                     - pts.value) * w
            return np.clip(np.nan_to_num(r, nan=1e12), -1e12, 1e12)

        def jac(x: np.ndarray) -> np.ndarray:
            th = full(x)
            with np.errstate(over="ignore", invalid="ignore"):
                g = equations.gradient_to_fit(
                    equations.angle_gradient(th, pts.L_mm, pts.t_mm, pts.pressure_pa), th)
            return np.clip(np.nan_to_num(g[:, free] * w[:, None], nan=0.0), -1e12, 1e12)

        sol = least_squares(fun, q_start[free], jac=jac, bounds=(lo[free], hi[free]),
                            x_scale="jac", method="trf", max_nfev=2000)
        q = q_start.copy()
        q[free] = sol.x
        return q

    w = np.ones_like(pts.value)
    q = solve(q0, w)
    sd, rel = _scatter(equations.from_fit(q), pts)
    if weighted:
        w = _weights(equations.from_fit(q), pts, sd, rel)
        q = solve(q, w)
        sd, rel = _scatter(equations.from_fit(q), pts)
        w = _weights(equations.from_fit(q), pts, sd, rel)
    theta = equations.from_fit(q)
    cov = _covariance(theta, pts, w, free)
    err = _predict(theta, pts) - pts.value
    return ModelParameters(
        form=form, names=names, values=tuple(float(v) for v in theta),
        covariance=tuple(tuple(float(v) for v in row) for row in cov),
        residual_sd=sd, residual_rel=rel,
        fixed=tuple(n for n, f in zip(names, free, strict=True) if not f),
        rmse=float(np.sqrt(np.mean(err ** 2))), max_error=float(np.max(np.abs(err))),
        n_points=len(pts.value), n_curves=pts.n_curves)


def _predict(theta: np.ndarray, pts: Points) -> np.ndarray:
    return equations.angle_deg(theta, pts.L_mm, pts.t_mm, pts.pressure_pa)


def _x(theta: np.ndarray, pts: Points) -> np.ndarray:
    return pts.pressure_pa / equations.tau_pa(theta, pts.t_mm)


def _scatter(theta: np.ndarray, pts: Points) -> tuple[float, float]:
    m = _predict(theta, pts)
    return bands.fit_scatter(pts.value - m, m, _x(theta, pts))


def _weights(theta: np.ndarray, pts: Points, sd: float, rel: float) -> np.ndarray:
    var = bands.scatter_variance(sd, rel, _predict(theta, pts), _x(theta, pts))
    return 1.0 / np.sqrt(np.maximum(var, 1e-12 * max(sd, 1e-9) ** 2))


def _covariance(theta: np.ndarray, pts: Points, w: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Covariance of the fit coordinates; J's columns are scaled to unit norm before the
    pseudo-inverse so that its cut-off only drops directions the data do not fix."""
    k = len(theta)
    g = equations.angle_gradient(theta, pts.L_mm, pts.t_mm, pts.pressure_pa)
    J = equations.gradient_to_fit(g, theta)[:, free] * w[:, None]
    r = (_predict(theta, pts) - pts.value) * w
    n, kf = J.shape
    cov = np.zeros((k, k))
    if n <= kf:
        return cov
    s2 = float(r @ r) / (n - kf)
    norm = np.linalg.norm(J, axis=0)
    s = np.where(norm > 0, 1.0 / np.where(norm > 0, norm, 1.0), 0.0)
    Js = J * s
    sub = np.linalg.pinv(Js.T @ Js) * np.outer(s, s) * s2
    idx = np.flatnonzero(free)
    cov[np.ix_(idx, idx)] = sub
    return cov


def leave_one_design_out(pts: Points, form: str, level: float = 0.95,
                         start: np.ndarray | None = None) -> dict[str, object]:
    """Refit without each design in turn and predict it: RMSE and max error (model unit)
    per held-out design and pooled, and the fraction of held-out points inside the band.

    A held-out design whose L or t lies outside the range of the remaining designs is
    an extrapolation (``"extrapolated": true``); the pooled figures are also given over
    the interpolated designs alone (``*_interpolated``), which is what a user asking
    inside the fitted domain should expect.

    ``band_scale`` is the factor on the band's half-width that would have put ``level``
    of the held-out (interpolated) points inside it; ``coverage_calibrated`` is the
    coverage with that factor when each design is judged by the factor estimated from
    the other designs only (a jackknife, so the figure is not self-fulfilling)."""
    designs = np.unique(pts.curve)
    if len(designs) < 2:
        return {"form": form, "n_designs": int(len(designs)), "available": False}
    rows = []
    all_err, inside, interior, standardized = [], [], [], []
    for i in designs:
        held = pts.curve == i
        train, test = pts.subset(~held), pts.subset(held)
        if len(np.unique(train.L_mm)) < 1:
            continue
        params = joint_fit(train, form, start=start)
        m, lo, hi = bands.angle_band(params, test.L_mm, test.t_mm, test.pressure_pa, level)
        err = m - test.value
        ins = (test.value >= lo) & (test.value <= hi)
        half = 0.5 * (hi - lo) / (params.band_scale * bands.z_value(level))
        standardized.append(np.abs(err) / np.where(half > 0, half, np.inf))
        L0, t0 = float(test.L_mm[0]), float(test.t_mm[0])
        outside = not (train.L_mm.min() <= L0 <= train.L_mm.max()
                       and train.t_mm.min() <= t0 <= train.t_mm.max())
        all_err.append(err)
        inside.append(ins)
        interior.append(np.full(err.shape, not outside))
        rows.append({"L_mm": L0, "t_mm": t0, "extrapolated": outside,
                     "rmse": float(np.sqrt(np.mean(err ** 2))),
                     "max_error": float(np.max(np.abs(err))),
                     "coverage": float(np.mean(ins)), "n_points": int(len(err))})
    e = np.concatenate(all_err)
    ins_all = np.concatenate(inside)
    mid = np.concatenate(interior)
    # Band calibration on the held-out designs (interpolated ones when there are any),
    # and its honest coverage: each design judged with the scale estimated without it.
    z = bands.z_value(level)
    use = [j for j, r in enumerate(rows) if not r["extrapolated"]] or list(range(len(rows)))
    scale = band_scale_from_lodo([standardized[j] for j in use], level)
    inside_cal = []
    for i, r in enumerate(rows):
        s_i = band_scale_from_lodo([standardized[j] for j in use if j != i], level)
        ok = standardized[i] <= s_i * z
        r["coverage_calibrated"] = float(np.mean(ok))
        inside_cal.append(ok)
    cal = np.concatenate(inside_cal)
    return {"band_scale": scale,
            "coverage_calibrated": float(np.mean(cal)),
            "coverage_calibrated_interpolated": nan_to_none(float(np.mean(cal[mid]))
                                                            if mid.any() else math.nan),
"form": form, "available": True, "level": level, "n_designs": len(rows),
            "rmse": float(np.sqrt(np.mean(e ** 2))), "max_error": float(np.max(np.abs(e))),
            "coverage": float(np.mean(ins_all)),
            "n_interpolated": int(sum(not r["extrapolated"] for r in rows)),
            "rmse_interpolated": nan_to_none(float(np.sqrt(np.mean(e[mid] ** 2)))
                                             if mid.any() else math.nan),
            "coverage_interpolated": nan_to_none(float(np.mean(ins_all[mid]))
                                                 if mid.any() else math.nan),
            "mean_design_coverage": float(np.mean([r["coverage"] for r in rows])),
            "designs": rows}


def band_scale_from_lodo(standardized: list[np.ndarray], level: float) -> float:
    """Smallest factor (>= 1) on the band's half-width that puts a fraction ``level`` of
    the held-out points inside it; ``standardized`` holds |error| / band sd per design."""
    r = np.concatenate(standardized) if standardized else np.empty(0)
    r = r[np.isfinite(r)]
    if r.size == 0:
        return 1.0
    return max(1.0, float(np.quantile(r, level)) / bands.z_value(level))


def nan_to_none(x: float) -> float | None:
    return None if x is None or not math.isfinite(x) else float(x)
