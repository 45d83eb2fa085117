"""What is left after the selected effects: its size against the noise floor, whether it
has structure, and where along the curves it sits.

``unexplained_rms_deg`` = sqrt(max(rmse_after^2 - floor^2, 0)): the part of the
cross-validated error that replicate scatter does not explain. What remains is
*structured* when the structure test finds it along the curves (_structure.py) or when
the cross-validated error exceeds ``EXCESS_RATIO`` x a replicate floor. Where: the
out-of-fold residuals binned by phase (loading, hold, unloading) and by thirds of the
pressure range; the bins whose mean residual is largest are named.
"""

from __future__ import annotations

import math

import numpy as np

from surrogate.calibration._data import Observations
from surrogate.calibration._noise import NoiseFloor

EXCESS_RATIO = 1.3
PHASES = ((1.0, "loading"), (0.0, "hold"), (-1.0, "unloading"))


def residual_summary(obs: Observations, resid_cv: np.ndarray, rmse_after: float,
                     noise: NoiseFloor, structure: dict) -> dict:
    floor = noise.rms_deg
    has_floor = math.isfinite(floor)
    unexplained = math.sqrt(max(rmse_after**2 - floor**2, 0.0)) if has_floor else None
    excess = has_floor and noise.source == "replicates" and rmse_after > EXCESS_RATIO * floor
    structured = bool(structure["structured"] or excess)
    p = obs.pressure_pa
    edges = np.quantile(p, [0, 1 / 3, 2 / 3, 1]) if p.size else np.zeros(4)
    third = np.clip(np.searchsorted(edges[1:-1], p, side="right"), 0, 2)
    bins = []
    for d, phase in PHASES:
        for j, name in enumerate(("low", "mid", "high")):
            m = (obs.direction == d) & (third == j)
            if m.sum() < 3:
                continue
            r = resid_cv[m]
            bins.append({"phase": phase, "pressure": name,
                         "pressure_range_pa": [float(p[m].min()), float(p[m].max())],
                         "n": int(m.sum()), "mean_residual_deg": float(r.mean()),
                         "rms_residual_deg": float(np.sqrt(np.mean(r**2)))})
    bins.sort(key=lambda b: -abs(b["mean_residual_deg"]))
    sentence = ""
    if structured:
        top = bins[:2]
        where = "; ".join(f"{b['phase']} at {b['pressure']} pressure "
                          f"({b['pressure_range_pa'][0]:.0f}-{b['pressure_range_pa'][1]:.0f}"
                          f" Pa): model - data {b['mean_residual_deg']:+.2f} deg on average"
                          for b in top)
        size = (f"{unexplained:.2f} deg RMS beyond the {floor:.2f} deg floor"
                if unexplained is not None else "of unknown size (no noise floor)")
        why = []
        if excess:
            why.append(f"the cross-validated error is {rmse_after / floor:.1f} x the floor")
        if structure["structured"]:
            why.append(f"the residuals run along the curves (lag-1 z = "
                       f"{structure['z_lag1']:.1f}, runs z = {structure['z_runs']:.1f})")
        sentence = ("What remains is NOT noise (" + "; ".join(why) + "): an effect outside "
                    f"the catalogue acts on these data, {size}, largest where {where}. This "
                    "calibration does not explain it; look at the residual plot before "
                    "trusting the augmented model.")
    return {"structured": structured, "unexplained_rms_deg": unexplained, "where": bins,
            "sentence": sentence}
