"""Least-squares fit of the baseline (per family) together with a set of effects.

Free baseline parameters per family: a (deg/mm), and the tau law as (tau_ref, a_t) with
tau_ref = a_t log10(b_t t_ref) at the family's geometric-mean thickness t_ref (better
conditioned than (a_t, b_t)). With one thickness in a family only tau_ref is free (a_t
stays at the starting value: a_t and b_t are not separately identifiable). When a
"parameter" effect (stiffness_scale, membrane_thickness_bias) is in the set, a_t and b_t
are pinned at the starting values: that effect then carries the change of tau.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from surrogate.calibration._data import Observations
from surrogate.calibration._effects import EFFECTS
from surrogate.calibration._forward import angle_model

# Internal (fit) name, physical name, and transforms for reparametrised parameters.
INTERNAL = {"theta_max_deg": "inv_theta_max_per_deg"}
# Residuals are capped at +/- this (deg) while fitting: a trial step into a region where
# the exponential overflows then stays a large finite penalty with a finite Jacobian.
R_CAP_DEG = 1e6


@dataclass(frozen=True)
class Layout:
    """Where each free number lives in the parameter vector."""

    effects: tuple[str, ...]
    pinned_tau: bool
    fam_free_a: tuple[int, ...]
    fam_free_tau: tuple[int, ...]
    fam_free_at: tuple[int, ...]
    t_ref: np.ndarray
    effect_names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray

    @property
    def k(self) -> int:
        return self.lower.size


def _effect_params(effects: tuple[str, ...]):
    out = []
    for eid in effects:
        for p in EFFECTS[eid].parameters:
            if p.name == "theta_max_deg":
                out.append((INTERNAL[p.name], 0.0, 1.0 / p.fit_bounds[0], 1e-3))
            else:
                out.append((p.name, p.fit_bounds[0], p.fit_bounds[1], p.start))
    return out


def make_layout(obs: Observations, effects: tuple[str, ...], nominal: np.ndarray,
                pin_tau: bool = False) -> Layout:
    pinned = pin_tau or any(EFFECTS[e].kind == "parameter" for e in effects)
    present = sorted(set(obs.family.tolist()))
    t_ref = np.ones(nominal.shape[0])
    free_at = []
    for f in present:
        ts = np.unique(obs.t_mm[obs.family == f])
        t_ref[f] = float(np.exp(np.mean(np.log(ts))))
        if ts.size >= 2 and not pinned:
            free_at.append(f)
    lower = [-np.inf] * len(present)
    upper = [np.inf] * len(present)
    free_tau = [] if pinned else present
    lower += [1.0] * len(free_tau) + [1.0] * len(free_at)
    upper += [1e6] * len(free_tau) + [1e6] * len(free_at)
    eps = _effect_params(effects)
    lower += [lo for _, lo, _, _ in eps]
    upper += [hi for _, _, hi, _ in eps]
    return Layout(effects, pinned, tuple(present), tuple(free_tau), tuple(free_at), t_ref,
                  tuple(n for n, _, _, _ in eps), np.array(lower, float), np.array(upper, float))


def start_vector(layout: Layout, nominal: np.ndarray) -> np.ndarray:
    x = [nominal[f, 0] for f in layout.fam_free_a]
    x += [nominal[f, 1] * np.log10(nominal[f, 2] * layout.t_ref[f]) for f in layout.fam_free_tau]
    x += [nominal[f, 1] for f in layout.fam_free_at]
    x += [s for _, _, _, s in _effect_params(layout.effects)]
    return np.clip(np.array(x, float), layout.lower, layout.upper)


def unpack(layout: Layout, nominal: np.ndarray, x: np.ndarray
           ) -> tuple[np.ndarray, dict[str, float]]:
    fam = nominal.copy()
    i = 0
    for f in layout.fam_free_a:
        fam[f, 0] = x[i]
        i += 1
    tau_ref = {}
    for f in layout.fam_free_tau:
        tau_ref[f] = x[i]
        i += 1
    for f in layout.fam_free_at:
        fam[f, 1] = x[i]
        i += 1
    for f, tr in tau_ref.items():  # tau_ref = a_t log10(b_t t_ref) -> b_t
        fam[f, 2] = 10.0 ** (tr / fam[f, 1]) / layout.t_ref[f]
    values = {name: float(v) for name, v in zip(layout.effect_names, x[i:], strict=False)}
    return fam, values


@dataclass
class FitResult:
    """A fitted model: family parameters, effect values, and the statistics of the fit."""

    effects: tuple[str, ...]
    families: np.ndarray
    values: dict[str, float]
    x: np.ndarray
    sse: float
    n: int
    k: int
    cov: np.ndarray
    layout: Layout
    success: bool
    pinned: bool
    residual: np.ndarray = field(repr=False)

    @property
    def bic(self) -> float:
        return self.n * float(np.log(max(self.sse, 1e-300) / self.n)) + self.k * np.log(self.n)

    def effect_sd(self) -> dict[str, float]:
        """Standard errors of the effect parameters (physical names)."""
        n_eff = len(self.layout.effect_names)
        sd = np.sqrt(np.clip(np.diag(self.cov), 0.0, np.inf))[self.k - n_eff:]
        return dict(zip(self.layout.effect_names, sd.tolist(), strict=False))


def fit(obs: Observations, effects: tuple[str, ...], nominal: np.ndarray,
        x0: np.ndarray | None = None, pin_tau: bool = False) -> FitResult:
    """Least squares over the baseline and the effects' parameters (``pin_tau``: keep
    every family's a_t, b_t at the starting values)."""
    layout = make_layout(obs, effects, nominal, pin_tau)
    if x0 is None or x0.size != layout.k:
        x0 = start_vector(layout, nominal)
    x0 = np.clip(x0, layout.lower, layout.upper)

    def residual(x: np.ndarray) -> np.ndarray:
        fam, values = unpack(layout, nominal, x)
        r = angle_model(obs, fam, values) - obs.angle_deg
        return np.clip(np.nan_to_num(r, nan=R_CAP_DEG), -R_CAP_DEG, R_CAP_DEG)

    res = least_squares(residual, x0, bounds=(layout.lower, layout.upper), x_scale="jac",
                        method="trf", max_nfev=400 * max(layout.k, 1))
    fam, values = unpack(layout, nominal, res.x)
    r = res.fun
    sse = float(r @ r)
    cov = _cluster_covariance(res.jac, r, obs.curve)
    return FitResult(effects, fam, values, res.x, sse, obs.n, layout.k, cov, layout,
                     bool(res.success), layout.pinned_tau, r)


def _cluster_covariance(jac: np.ndarray, r: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """Covariance of the fitted parameters, robust to scatter shared within a curve
    (specimen-to-specimen variation): the sandwich estimator clustered by curve,
    (J'J)^-1 [sum_c (J_c' r_c)(J_c' r_c)'] (J'J)^-1 x G/(G-1)."""
    bread = np.linalg.pinv(jac.T @ jac)
    g = np.zeros((int(curve.max()) + 1, jac.shape[1]))
    np.add.at(g, curve, jac * r[:, None])
    n_groups = g.shape[0]
    meat = g.T @ g * n_groups / max(n_groups - 1, 1)
    return bread @ meat @ bread


def curve_folds(n_curves: int, k: int = 5) -> list[np.ndarray]:
    """Grouped K-fold by curve: curve i is held out in fold i mod K (replicates, which
    are usually listed together, land in different folds). K is reduced to ``n_curves``
    (leave-one-curve-out), so no fold is empty and every fit sees at least one curve."""
    if n_curves < 2 or k < 2:
        raise ValueError(f"cross-validation by curve needs >= 2 curves and folds, got "
                         f"{n_curves} curves, {k} folds (check_calibratable says so first)")
    k = min(k, n_curves)
    return [np.arange(i, n_curves, k) for i in range(k)]


def cross_validate(obs: Observations, effects: tuple[str, ...], nominal: np.ndarray,
                   full: FitResult | None = None, k: int = 5, pin_tau: bool = False
                   ) -> tuple[float, np.ndarray]:
    """RMS error (deg) of predicting each held-out curve from a fit that did not see it;
    returns (rmse, per-row out-of-fold residual). Families absent from a training set
    are predicted with the starting (nominal) parameters."""
    resid = np.empty(obs.n)
    for held in curve_folds(obs.n_curves, k):
        train = obs.subset(np.setdiff1d(np.arange(obs.n_curves), held))
        test_rows = np.isin(obs.curve, held)
        test = obs.subset(held)
        x0 = None
        if full is not None and make_layout(train, effects, nominal, pin_tau).k == full.k:
            x0 = full.x
        f = fit(train, effects, nominal, x0, pin_tau)
        resid[test_rows] = angle_model(test, f.families, f.values) - test.angle_deg
    return float(np.sqrt(np.mean(resid**2))), resid
