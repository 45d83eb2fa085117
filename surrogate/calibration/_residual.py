"""What is left after the selected effects: its size, whether replicate scatter explains
it, and where along the curves it sits.

The replicate noise floor is the error a perfect model of each design's mean makes on an
unseen specimen, measured on the same specimens as the cross-validation; on FE data the
right model's cross-validated error sits within a few % of it (1.00-1.05 in
tests/test_calibration_loop.py). So with a replicate floor:

    unexplained_rms_deg = sqrt(max(rmse^2 - sd_baseline^2 - floor^2, 0))

(sd_baseline: the baseline's own uncertainty for an FE solve, from its band -- an
emulator's interpolation error is not a missing effect), and what remains is *structured*
when sqrt(rmse^2 - sd_baseline^2) exceeds the floor by more than ``EXCESS_RATIO`` (or 2
relative standard errors of their ratio, when larger: ``excess_limit``), or when replicates
share a residual: for readings of curve c and the mean out-of-fold residual of the other
replicates at the same time,

    S^2 = mean( r_c(t) x mean_{c' != c} r_c'(t) )

is unbiased for the squared systematic residual (independent specimens contribute 0); it
counts when S^2 - sd_baseline^2 exceeds 3 standard errors (spread of the per-curve means)
and a quarter of the floor squared. Without replicates, the within-curve structure test
(_structure.py) decides and the size is sqrt(max(rmse^2 - floor^2, 0)). Where: the
out-of-fold residuals binned by phase (loading, hold, unloading) and by thirds of the
pressure range; the bins whose mean residual is largest are named.
"""

from __future__ import annotations

import math

import numpy as np

from surrogate.calibration._data import Observations
from surrogate.calibration._noise import NoiseFloor

Z_SYSTEMATIC = 3.0
MIN_SIZE_FRACTION = 0.25
EXCESS_RATIO = 1.10
PHASES = ((1.0, "loading"), (0.0, "hold"), (-1.0, "unloading"))


def systematic_residual(obs: Observations, resid: np.ndarray) -> dict | None:
    """S^2, its standard error and the number of curves used; None without replicates."""
    per_curve = []
    for g in np.unique(obs.group):
        curves = np.unique(obs.curve[obs.group == g])
        if curves.size < 2:
            continue
        rows_of = {int(c): np.flatnonzero(obs.curve == c) for c in curves}
        for c, rows in rows_of.items():
            x = obs.time_s[rows] if obs.has_time else np.arange(rows.size, dtype=float)
            others = []
            for c2, rows2 in rows_of.items():
                if c2 == c:
                    continue
                x2 = obs.time_s[rows2] if obs.has_time else np.arange(rows2.size, dtype=float)
                others.append(np.interp(x, x2, resid[rows2], left=np.nan, right=np.nan))
            o = np.array(others)
            ok = np.any(np.isfinite(o), axis=0) & np.isfinite(resid[rows])
            if ok.sum() < 2:
                continue
            mean = np.nanmean(o[:, ok], axis=0)
            per_curve.append(float(np.mean(resid[rows][ok] * mean)))
    if len(per_curve) < 3:
        return None
    v = np.array(per_curve)
    return {"s2_deg2": float(v.mean()), "se_deg2": float(v.std(ddof=1) / math.sqrt(v.size)),
            "curves": int(v.size)}


def residual_summary(obs: Observations, resid_cv: np.ndarray, rmse_after: float,
                     noise: NoiseFloor, structure: dict, baseline_var: float = 0.0) -> dict:
    floor = noise.rms_deg
    replicates = noise.source == "replicates" and math.isfinite(floor)
    sys_ = systematic_residual(obs, resid_cv) if replicates else None
    why = []
    limit = None
    if replicates and math.isfinite(rmse_after):
        model_part2 = max(rmse_after**2 - baseline_var, 0.0)
        unexplained = math.sqrt(max(model_part2 - floor**2, 0.0))
        if floor > 0:
            ratio = math.sqrt(model_part2) / floor
        else:  # replicates that agree exactly (copies of one curve): any misfit counts
            ratio = math.inf if model_part2 > 0 else 0.0
        limit = excess_limit(noise, cv_rel_se(obs, resid_cv, baseline_var))
        excess = ratio > limit
        if excess:
            why.append(f"the cross-validated error is {ratio:.2f} x the replicate floor, "
                       f"beyond its {limit:.2f} x allowance"
                       + (" net of the baseline's own uncertainty" if baseline_var else ""))
        shared = bool(sys_ is not None and sys_["s2_deg2"] - baseline_var
                      > Z_SYSTEMATIC * sys_["se_deg2"]
                      and sys_["s2_deg2"] - baseline_var >= (MIN_SIZE_FRACTION * floor) ** 2)
        if shared:
            why.append(f"replicates share a residual of "
                       f"{math.sqrt(sys_['s2_deg2'] - baseline_var):.2f} deg RMS")
        structured = excess or shared
    else:
        has_floor = math.isfinite(floor) and math.isfinite(rmse_after)
        unexplained = math.sqrt(max(rmse_after**2 - floor**2, 0.0)) if has_floor else None
        structured = bool(structure["structured"])
        why.append(f"the residuals run along the curves (lag-1 z = "
                   f"{structure['z_lag1']:.1f}, runs z = {structure['z_runs']:.1f})")
    bins = where(obs, resid_cv)
    sentence = ""
    if structured:
        top = bins[:2]
        at = "; ".join(f"{b['phase']} at {b['pressure']} pressure "
                       f"({b['pressure_range_pa'][0]:.0f}-{b['pressure_range_pa'][1]:.0f} Pa)"
                       f": model - data {b['mean_residual_deg']:+.2f} deg on average"
                       for b in top)
        size = (f"{unexplained:.2f} deg RMS beyond the floor" if unexplained is not None
                else "of unknown size (no noise floor)")
        sentence = (f"What remains is NOT noise ({'; '.join(why)}): an effect outside the "
                    f"catalogue acts on these data, {size}, largest where {at}. No "
                    "catalogued effect explains it; look at the residual plot before "
                    "trusting the model.")
    return {"structured": structured, "unexplained_rms_deg": unexplained, "where": bins,
            "systematic": sys_, "sentence": sentence, "excess_allowance": limit if replicates
            and math.isfinite(rmse_after) else None}


def cv_rel_se(obs: Observations, resid_cv: np.ndarray, baseline_var: float = 0.0) -> float:
    """Relative standard error of the cross-validated error sqrt(rmse^2 - baseline_var),
    from the spread of the per-curve mean squares of ``resid_cv``: a specimen's scatter is
    shared along its curve, so the curves, not the readings, are the independent units
    (as for the floor's ``rel_se``); NaN with fewer than two curves."""
    ms = [float(np.mean(resid_cv[rows] ** 2)) for c in range(obs.n_curves)
          if (rows := np.flatnonzero((obs.curve == c) & np.isfinite(resid_cv))).size]
    model_part2 = float(np.mean(resid_cv[np.isfinite(resid_cv)] ** 2)) - baseline_var
    if len(ms) < 2 or model_part2 <= 0:
        return float("nan")
    return 0.5 * float(np.std(ms, ddof=1)) / math.sqrt(len(ms)) / model_part2


def excess_limit(noise: NoiseFloor, cv_rel: float = float("nan")) -> float:
    """How far above the floor a right model's cross-validated error may be: EXCESS_RATIO,
    or 1 + 2 relative standard errors of their ratio when that is larger. Both are
    measured on the same few specimens, whose scatter is shared along each curve: with 9
    curves of 3 % stiffness scatter read against the gauge pressure, a right model's ratio
    ranged over 0.80-1.89 in 60 noise draws (docs/calibration.md, "What is left"). The two
    relative errors are added in quadrature, their positive correlation (a specimen far
    off raises both) left out, which errs towards the wider allowance."""
    rel_f = noise.rel_se if math.isfinite(noise.rel_se) else 0.0
    rel_c = cv_rel if math.isfinite(cv_rel) else 0.0
    return max(EXCESS_RATIO, 1.0 + 2.0 * math.hypot(rel_f, rel_c))


def where(obs: Observations, resid: np.ndarray) -> list[dict]:
    """Out-of-fold residuals by phase and pressure third, largest mean first."""
    p = obs.pressure_pa
    edges = np.quantile(p, [0, 1 / 3, 2 / 3, 1]) if p.size else np.zeros(4)
    third = np.clip(np.searchsorted(edges[1:-1], p, side="right"), 0, 2)
    bins = []
    for d, phase in PHASES:
        for j, name in enumerate(("low", "mid", "high")):
            m = (obs.direction == d) & (third == j) & np.isfinite(resid)
            if m.sum() < 3:
                continue
            r = resid[m]
            bins.append({"phase": phase, "pressure": name,
                         "pressure_range_pa": [float(p[m].min()), float(p[m].max())],
                         "n": int(m.sum()), "mean_residual_deg": float(r.mean()),
                         "rms_residual_deg": float(np.sqrt(np.mean(r**2)))})
    bins.sort(key=lambda b: -abs(b["mean_residual_deg"]))
    return bins
