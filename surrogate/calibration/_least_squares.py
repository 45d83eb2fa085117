"""Least squares of an augmented model, its clustered standard errors, BIC, and the
cross-validation by curve.

Standard errors are the sandwich estimator clustered by curve (specimen-to-specimen
scatter is shared along a curve, so it counts in full); BIC = n ln(SSE/n) + k ln n.
With the pressure-by-volume channel (``AugmentedModel.pressure_weight`` > 0) the
residuals are the angles' and, beside them, the gauge pressures' at the injected volume
times the weight (deg per Pa: the ratio of the two noise floors); SSE, n, BIC and the
clustering count both, and ``residual`` stays the angles' (the structure tests').
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from surrogate.calibration._augmented_model import AugmentedModel
from surrogate.calibration._data import Observations

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
    #: the pressure channel's weighted residual (deg-equivalent), None without it
    residual_pressure: np.ndarray | None = field(default=None, repr=False)

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


def _capped(r: np.ndarray) -> np.ndarray:
    return np.clip(np.nan_to_num(r, nan=R_CAP_DEG), -R_CAP_DEG, R_CAP_DEG)


def pressure_residual(model: AugmentedModel, x: np.ndarray) -> np.ndarray | None:
    """The pressure channel's residual at every row, weighted (deg-equivalent); None
    without the channel."""
    if model.pressure_weight <= 0.0:
        return None
    return model.pressure_weight * (model.gauge_pressures(x) - model.obs.pressure_pa)


def _raw_residual_fn(model: AugmentedModel) -> Callable[[np.ndarray], np.ndarray]:
    y = model.obs.angle_deg

    def residual(x: np.ndarray) -> np.ndarray:
        r = model.angles(x) - y
        rp = pressure_residual(model, x)
        return _capped(r if rp is None else np.concatenate([r, rp]))

    return residual


def fit(model: AugmentedModel, x0: np.ndarray | None = None) -> FitResult:
    """Least squares of the residuals weighted for the specimens' scatter
    (``AugmentedModel.whiten``; ordinary least squares without it): SSE, BIC, Jacobian
    and covariance are the weighted ones, ``residual`` and ``residual_pressure`` the
    unweighted (deg)."""
    lay = model.layout
    raw = _raw_residual_fn(model)
    n = model.obs.n
    if lay.k == 0:
        r0 = raw(np.zeros(0))
        r = model.whiten(r0)
        return FitResult(model, np.zeros(0), float(r @ r), r.size, np.zeros((0, 0)), True,
                         r0[:n], residual_pressure=r0[n:] if r0.size > n else None)
    start = lay.start if x0 is None else x0
    start = np.clip(start, lay.lower, lay.upper)

    def solve(x_start: np.ndarray):
        return least_squares(lambda x: model.whiten(raw(x)), x_start,
                             bounds=(lay.lower, lay.upper), x_scale="jac", method="trf",
                             diff_step=1e-4, max_nfev=60 * max(lay.k, 1))

    res = solve(start)
    # a start on a bound (a change of the design whose nominal value sits on the box's
    # face: dt >= 0 at t = 0.5 mm) can stay there while the optimum is inside; a second
    # start a quarter into the range, the better fit kept (a 0.05 mm thicker membrane at
    # t = 0.5 was fitted as dt = 2e-10, 2026-12-06)
    inner = start.copy()
    span = lay.upper - lay.lower
    on_low, on_high = start <= lay.lower, start >= lay.upper
    inner[on_low] = (lay.lower + 0.25 * span)[on_low]
    inner[on_high] = (lay.upper - 0.25 * span)[on_high]
    if x0 is None and np.any((on_low | on_high) & np.isfinite(span) & (span > 0)):
        other = solve(inner)
        if other.cost < res.cost:
            res = other
    r = res.fun
    r0 = r if model.scatter is None else raw(res.x)
    cov = cluster_covariance(res.jac, r, model.residual_specimens())
    return FitResult(model, res.x, float(r @ r), r.size, cov, bool(res.success), r0[:n],
                     res.jac, residual_pressure=r0[n:] if r0.size > n else None)


def cluster_covariance(jac: np.ndarray, r: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """(J'J)^-1 [sum_c (J_c' r_c)(J_c' r_c)'] (J'J)^-1 x G/(G-1): covariance of the fitted
    parameters robust to scatter shared within a cluster (a specimen: its runs share its
    stiffness)."""
    bread = np.linalg.pinv(jac.T @ jac)
    g = np.zeros((int(curve.max()) + 1, jac.shape[1]))
    np.add.at(g, curve, jac * r[:, None])
    n_groups = g.shape[0]
    meat = g.T @ g * n_groups / max(n_groups - 1, 1)
    return bread @ meat @ bread


def curve_folds(n_curves: int, k: int = 5) -> list[np.ndarray]:
    """Grouped K-fold: unit i (a curve, or a specimen with all its runs) is held out in
    fold i mod K (replicates, usually listed together, land in different folds); K is
    reduced to ``n_curves``, the number of units."""
    if n_curves < 2 or k < 2:
        raise ValueError(f"cross-validation by curve needs >= 2 curves and folds, got "
                         f"{n_curves} curves, {k} folds (check_calibratable says so first)")
    k = min(k, n_curves)
    return [np.arange(i, n_curves, k) for i in range(k)]


@dataclass(frozen=True)
class CrossValidation:
    """Out-of-fold residuals per row: the angle's (deg) and, with the pressure channel,
    the gauge pressure's weighted (deg-equivalent; None without it)."""

    angle: np.ndarray
    pressure: np.ndarray | None

    @property
    def rmse_deg(self) -> float:
        """RMS angle error (deg); inf when a held-out curve falls past the baseline."""
        r = self.angle
        return float(np.sqrt(np.mean(r**2))) if np.all(np.isfinite(r)) else float("inf")

    @property
    def joint(self) -> np.ndarray:
        """Both channels' residuals (angle rows, then pressure rows)."""
        return self.angle if self.pressure is None else np.concatenate([self.angle,
                                                                        self.pressure])

    @property
    def rmse_joint(self) -> float:
        """RMS of both channels (deg-equivalent): what the selection compares."""
        r = self.joint
        return float(np.sqrt(np.mean(r**2))) if np.all(np.isfinite(r)) else float("inf")

    def curves(self, curve: np.ndarray) -> np.ndarray:
        return curve if self.pressure is None else np.concatenate([curve, curve])


def cross_validate(obs: Observations, make: Callable[[Observations], AugmentedModel],
                   full: FitResult, k: int = 5) -> CrossValidation:
    """Predicting each held-out curve from a fit that did not see it, nor any other run
    of its specimen (folds by specimen; by curve without runs): the per-row
    out-of-fold residuals (NaN where a held-out curve falls past the baseline's range).
    A family absent from a training set keeps its open scales at 1 (the baseline as is)."""
    resid = np.empty(obs.n)
    resid_p = np.empty(obs.n) if full.model.pressure_weight > 0.0 else None
    specimen = obs.curve_specimen()   # a specimen's runs are held out together
    for held_specimens in curve_folds(obs.n_specimens, k):
        held = np.flatnonzero(np.isin(specimen, held_specimens))
        train = obs.subset(np.setdiff1d(np.arange(obs.n_curves), held))
        test = obs.subset(held)
        m_train = make(train)
        f = fit(m_train, _transfer(full, m_train))
        m_test = make(test)
        x = _transfer(f, m_test)
        rows = np.isin(obs.curve, held)
        resid[rows] = m_test.angles(x) - test.angle_deg
        if resid_p is not None:
            resid_p[rows] = pressure_residual(m_test, x)
    return CrossValidation(_finite_or_nan(resid), _finite_or_nan(resid_p))


def _finite_or_nan(r: np.ndarray | None) -> np.ndarray | None:
    return None if r is None else np.where(np.isfinite(r), r, np.nan)


def _transfer(f: FitResult, target: AugmentedModel) -> np.ndarray:
    """The fitted numbers of ``f`` in ``target``'s layout (by name; absent -> start)."""
    by_name = dict(zip(f.model.layout.names, f.x.tolist(), strict=True))
    lay = target.layout
    x = np.array([by_name.get(n, s) for n, s in zip(lay.names, lay.start, strict=True)])
    return x if lay.k else np.zeros(0)


def paired_cv(resid_a: np.ndarray, resid_b: np.ndarray, curve: np.ndarray) -> float:
    """How decisively held-out curves tell set A from set B: z of the mean difference of
    squared out-of-fold errors, A - B, with ``curve`` (per row: the specimen, whose
    scatter is shared along its curves and runs) as the independent units. Negative: A
    predicts unseen specimens better."""
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
