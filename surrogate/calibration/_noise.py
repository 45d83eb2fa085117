"""The noise floor: how far a replicate scatters around its design's mean curve.

Per group (same family, L, t and flow rate), all replicate curves are fitted together by a
flexible curve in pressure, c0 + c1 p + c2 p^2 + c3 p^3 + c4 exp(p / tau_g) (tau_g by a
1-D search), which follows any smooth systematic shape the model may miss but not the
specimen-to-specimen and reading scatter. The pooled residual RMS (dof-corrected) is the
noise floor: the error a perfect model of the design's mean would still make on a new
specimen. Without replicates the same fit is made per curve (reading scatter only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.calibration._data import Observations

N_FLEX = 6


@dataclass(frozen=True)
class NoiseFloor:
    rms_deg: float
    dof: int
    source: str  # "replicates" | "within-curve"
    groups: int


def _flex_sse(p: np.ndarray, y: np.ndarray) -> float:
    scale = max(float(np.max(np.abs(p))), 1.0)
    q = p / scale
    best = np.inf
    for tau in np.geomspace(0.05, 2.0, 40):
        X = np.column_stack([np.ones_like(q), q, q * q, q**3, np.expm1(q / tau)])
        coef, *_ = np.linalg.lstsq(X, y, rcond=None)
        r = y - X @ coef
        best = min(best, float(r @ r))
    return best


def noise_floor(obs: Observations) -> NoiseFloor:
    curves_per_group = np.bincount(
        np.unique(np.column_stack([obs.group, obs.curve]), axis=0)[:, 0])
    replicated = np.flatnonzero(curves_per_group >= 2)
    if replicated.size:
        keys, source = [(obs.group == g) for g in replicated], "replicates"
    else:
        keys, source = [(obs.curve == c) for c in range(obs.n_curves)], "within-curve"
    sse, dof = 0.0, 0
    for mask in keys:
        n = int(mask.sum())
        if n <= N_FLEX + 1:
            continue
        sse += _flex_sse(obs.pressure_pa[mask], obs.angle_deg[mask])
        dof += n - N_FLEX
    if dof == 0:
        return NoiseFloor(float("nan"), 0, "none", 0)
    return NoiseFloor(float(np.sqrt(sse / dof)), dof, source, len(keys))
