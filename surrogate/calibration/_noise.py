"""The noise floor: how far a new specimen scatters around its design's mean curve, at the
same point of its loading history.

Replicates (curves of one design at one flow rate) are compared where they are in the same
state: at the same time since the pump started (``time_s``; the other curves interpolated
linearly in time, within their range), or without ``time_s`` at the same reading number.
So a loading/unloading loop, a hold with creep or a flow-rate effect is not counted as
scatter: replicates share it. Each reading y of curve c is compared with the mean of the
k other replicates there; for independent specimens E[(y - mean_others)^2] =
sigma^2 (1 + 1/k), so

    floor^2 = sum (y - mean_others)^2 / (1 + 1/k) / N

counts both reading noise and specimen-to-specimen scatter in full: the error a perfect
model of the design's mean makes on a specimen it has not seen, which is what the
cross-validation by curve measures. Without replicates, the within-curve scatter from
second differences along time (reading noise only: an underestimate, ``source``
"within-curve").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.calibration._data import Observations


@dataclass(frozen=True)
class NoiseFloor:
    rms_deg: float
    dof: int
    source: str  # "replicates" | "within-curve" | "none"
    groups: int


def _history(obs: Observations, rows: np.ndarray) -> np.ndarray:
    return obs.time_s[rows] if obs.has_time else np.arange(rows.size, dtype=float)


def noise_floor(obs: Observations) -> NoiseFloor:
    sq, n_used, groups = 0.0, 0, 0
    for g in np.unique(obs.group):
        curves = np.unique(obs.curve[obs.group == g])
        if curves.size < 2:
            continue
        rows_of = {int(c): np.flatnonzero(obs.curve == c) for c in curves}
        used_here = 0
        for c, rows in rows_of.items():
            t = _history(obs, rows)
            others = []
            for c2, rows2 in rows_of.items():
                if c2 == c:
                    continue
                t2 = _history(obs, rows2)
                y2 = np.interp(t, t2, obs.angle_deg[rows2], left=np.nan, right=np.nan)
                others.append(y2)
            o = np.array(others)
            k = np.sum(np.isfinite(o), axis=0)
            ok = k >= 1
            if not np.any(ok):
                continue
            mean = np.nanmean(o[:, ok], axis=0)
            d = obs.angle_deg[rows][ok] - mean
            sq += float(np.sum(d**2 / (1.0 + 1.0 / k[ok])))
            n_used += int(ok.sum())
            used_here += 1
        groups += used_here > 0
    if n_used >= 4:
        return NoiseFloor(float(np.sqrt(sq / n_used)), n_used, "replicates", groups)
    return _within_curve(obs)


def _within_curve(obs: Observations) -> NoiseFloor:
    """Reading scatter from second differences along each curve's history:
    d = y_i - (w y_{i-1} + (1 - w) y_{i+1}), Var d = sigma^2 (1 + w^2 + (1 - w)^2)."""
    sq, n = 0.0, 0
    for c in range(obs.n_curves):
        rows = np.flatnonzero(obs.curve == c)
        if rows.size < 3:
            continue
        t = _history(obs, rows)
        y = obs.angle_deg[rows]
        w = (t[2:] - t[1:-1]) / np.maximum(t[2:] - t[:-2], 1e-12)
        d = y[1:-1] - (w * y[:-2] + (1 - w) * y[2:])
        sq += float(np.sum(d**2 / (1 + w**2 + (1 - w) ** 2)))
        n += d.size
    if n == 0:
        return NoiseFloor(float("nan"), 0, "none", 0)
    return NoiseFloor(float(np.sqrt(sq / n)), n, "within-curve", 0)
