"""The noise floor: how far a new specimen scatters around its design's mean curve.

Per group (same family, L, t and flow rate), all replicate curves are fitted together by a
flexible curve in pressure, c0 + c1 p + c2 p^2 + c3 p^3 + c4 exp(p / tau_g) (tau_g by a
1-D search), which follows any smooth systematic shape the model may miss but not the
specimen-to-specimen and reading scatter.

The pooled fit of m replicates follows their mean, so it absorbs 1/m of the
specimen-to-specimen part: its residual alone would underestimate that part by (m-1)/m in
variance (by half for m = 2). The floor therefore separates the two parts (a
random-effects decomposition):

    reading   s_r^2 = sum SSE(one flexible curve per curve) / sum (n_i - 6)
    specimen  s_u^2 = sum_g [SSE_g(one curve per group) - (N_g - 6) s_r^2] m_g/(m_g - 1)
                      / sum_g N_g                                  (clipped at 0)
    floor^2   = s_r^2 + s_u^2

-- the error a perfect model of the design's mean would make on a specimen it has not
seen, which is what the cross-validation by curve measures. Where curves are too short
for a fit of their own (at most 7 points), the pooled residual is used uncorrected
(``source`` "replicates-uncorrected", an underestimate). Without replicates the
within-curve fit alone gives the floor (reading scatter only, ``source`` "within-curve").
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
    source: str  # "replicates" | "replicates-uncorrected" | "within-curve" | "none"
    groups: int
    reading_deg: float = float("nan")   # within-curve part
    specimen_deg: float = float("nan")  # specimen-to-specimen part


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


def _pooled(obs: Observations, masks: list[np.ndarray]) -> tuple[float, int, int]:
    """Sum of flexible-fit SSE and dof over ``masks`` long enough to fit; how many."""
    sse, dof, used = 0.0, 0, 0
    for mask in masks:
        n = int(mask.sum())
        if n <= N_FLEX + 1:
            continue
        sse += _flex_sse(obs.pressure_pa[mask], obs.angle_deg[mask])
        dof += n - N_FLEX
        used += 1
    return sse, dof, used


def noise_floor(obs: Observations) -> NoiseFloor:
    pairs = np.unique(np.column_stack([obs.group, obs.curve]), axis=0)
    curves_per_group = np.bincount(pairs[:, 0])
    replicated = np.flatnonzero(curves_per_group >= 2)
    if not replicated.size:
        sse, dof, used = _pooled(obs, [obs.curve == c for c in range(obs.n_curves)])
        if dof == 0:
            return NoiseFloor(float("nan"), 0, "none", 0)
        rms = float(np.sqrt(sse / dof))
        return NoiseFloor(rms, dof, "within-curve", used, rms, float("nan"))

    rep_curves = pairs[np.isin(pairs[:, 0], replicated), 1]
    sse_r, dof_r, _ = _pooled(obs, [obs.curve == c for c in rep_curves])
    between, n_points, dof_g, groups, sse_g_all = 0.0, 0, 0, 0, 0.0
    for g in replicated:
        mask = obs.group == g
        sse_g, dof_one, used = _pooled(obs, [mask])
        if not used:
            continue
        m = int(curves_per_group[g])
        groups += 1
        sse_g_all += sse_g
        dof_g += dof_one
        n_points += int(mask.sum())
        if dof_r:
            between += (sse_g - dof_one * sse_r / dof_r) * m / (m - 1)
    if groups == 0:
        return NoiseFloor(float("nan"), 0, "none", 0)
    if dof_r == 0:  # curves too short for a fit of their own: pooled residual as is
        rms = float(np.sqrt(sse_g_all / dof_g))
        return NoiseFloor(rms, dof_g, "replicates-uncorrected", groups)
    reading2 = sse_r / dof_r
    specimen2 = max(between, 0.0) / n_points
    return NoiseFloor(float(np.sqrt(reading2 + specimen2)), dof_g, "replicates", groups,
                      float(np.sqrt(reading2)), float(np.sqrt(specimen2)))
