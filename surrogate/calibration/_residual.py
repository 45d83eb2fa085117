"""What is left after the selected effects: its size, whether replicate scatter explains
it, and where along the curves it sits.

A misfit the model makes is shared by replicate specimens at the same point of their
history; scatter is not. So the systematic part of the out-of-fold residual r is measured
by what replicates have in common: for readings of curve c and the mean residual of the
other replicates of its group at the same time (same reading number without time_s),

    S^2 = mean( r_c(t) x mean_{c' != c} r_c'(t) )

is unbiased for the squared systematic residual (independent specimens contribute 0);
its standard error comes from the spread of the per-curve means. The baseline's own
uncertainty for an FE solve (its band) is a systematic residual too, and is not
attributed to a missing effect: ``unexplained_rms_deg`` = sqrt(max(S^2 - sd_baseline^2,
0)). What remains is *structured* when S^2 - sd_baseline^2 exceeds 3 standard errors and
``unexplained_rms_deg`` is at least ``MIN_SIZE_FRACTION`` of the noise floor. Without
replicates, the within-curve structure test (_structure.py) decides and the size is
sqrt(max(rmse^2 - floor^2, 0)). Where: the out-of-fold residuals binned by phase
(loading, hold, unloading) and by thirds of the pressure range; the bins whose mean
residual is largest are named.
"""

from __future__ import annotations

import math

import numpy as np

from surrogate.calibration._data import Observations
from surrogate.calibration._noise import NoiseFloor

Z_SYSTEMATIC = 3.0
MIN_SIZE_FRACTION = 0.25
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
                x2 = obs.time_s[rows2] if obs.has_time else np.arange(rows2.size, float)
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
    has_floor = math.isfinite(floor)
    sys_ = systematic_residual(obs, resid_cv)
    if sys_ is not None:
        excess2 = sys_["s2_deg2"] - baseline_var
        unexplained = math.sqrt(max(excess2, 0.0))
        structured = bool(excess2 > Z_SYSTEMATIC * sys_["se_deg2"]
                          and (not has_floor or unexplained >= MIN_SIZE_FRACTION * floor))
        why = (f"replicates share a residual of {unexplained:.2f} deg RMS "
               f"(S^2 = {sys_['s2_deg2']:.2f} +/- {sys_['se_deg2']:.2f} deg^2"
               + (f", of which the baseline's own uncertainty {baseline_var:.2f}"
                  if baseline_var > 0 else "") + ")")
    else:
        unexplained = (math.sqrt(max(rmse_after**2 - floor**2, 0.0)) if has_floor
                       and math.isfinite(rmse_after) else None)
        structured = bool(structure["structured"])
        why = (f"the residuals run along the curves (lag-1 z = {structure['z_lag1']:.1f}, "
               f"runs z = {structure['z_runs']:.1f})")
    bins = where(obs, resid_cv)
    sentence = ""
    if structured:
        top = bins[:2]
        at = "; ".join(f"{b['phase']} at {b['pressure']} pressure "
                       f"({b['pressure_range_pa'][0]:.0f}-{b['pressure_range_pa'][1]:.0f} Pa)"
                       f": model - data {b['mean_residual_deg']:+.2f} deg on average"
                       for b in top)
        size = (f"{unexplained:.2f} deg RMS" if unexplained is not None else
                "of unknown size (no noise floor)")
        sentence = (f"What remains is NOT noise ({why}): an effect outside the catalogue "
                    f"acts on these data, {size}, largest where {at}. No catalogued effect "
                    "explains it; look at the residual plot before trusting the model.")
    return {"structured": structured, "unexplained_rms_deg": unexplained, "where": bins,
            "systematic": sys_, "sentence": sentence}


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
