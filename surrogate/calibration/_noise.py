"""The noise floor: how far a new specimen scatters around its design's mean, in the
model's terms (angle at the measured pressure), at the same point of its loading history.

Replicates (curves of one design at one flow rate, taken with one protocol) are compared
in the same state: each curve is cut into segments of one direction (loading, hold,
unloading: _history.py), and a reading in the k-th segment is compared with the other
replicates' k-th segment -- at the same pressure (their angle interpolated linearly in
pressure within the segment's range) for loading and unloading, at the same time since
the segment began for a hold. So a loading/unloading loop, creep during a hold or a
flow-rate effect is not counted as scatter (replicates share it), while the specimen's
own pressure-angle scatter is, as the model's cross-validated error counts it. For
independent specimens E[(y - mean_others)^2] = sigma^2 (1 + 1/k), k the number of others.
The others are other specimens: the runs of one specimen (the ``run`` column) share its
stiffness, so a run is never compared with its own specimen's runs, another specimen's
runs are averaged into one curve of that specimen before the mean, and k counts specimens
(3 runs of 2 specimens compared run with run made a floor of the runs' repeatability, not
of a new specimen's scatter):

    floor^2 = sum (y - mean_others)^2 / (1 + 1/k) / N

the error a perfect model of the design's mean makes on a specimen it has not seen.
``rel_se``: its relative standard error, from the spread of the per-specimen mean squares
(specimen scatter makes it 5-15 % with 3 specimens of 3-6 designs).
Without replicates: second differences along each curve of at least 8 readings (reading
noise only, no specimen scatter; the curvature between sparse readings adds to it:
``source`` "within-curve", a rough figure).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.calibration._data import Observations

MIN_READINGS = 4
WITHIN_CURVE_MIN_POINTS = 8  # sparser curves: second differences measure curvature


@dataclass(frozen=True)
class NoiseFloor:
    rms_deg: float
    dof: int
    source: str  # "replicates" | "within-curve" | "none"
    groups: int
    rel_se: float = float("nan")  # relative standard error of rms_deg (replicates)


def _history(obs: Observations, rows: np.ndarray) -> np.ndarray:
    return obs.time_s[rows] if obs.has_time else np.arange(rows.size, dtype=float)


def segments(direction: np.ndarray) -> np.ndarray:
    """Run index of each reading along one curve (a new run where the direction changes)."""
    return np.concatenate([[0], np.cumsum(direction[1:] != direction[:-1])]).astype(int)


EXTRAPOLATE_FRACTION = 0.15


def _other_at(obs: Observations, rows: np.ndarray, seg: np.ndarray, d: float, k: int,
              p: np.ndarray, t_rel: np.ndarray) -> np.ndarray:
    """The other curve's angle in its segment ``k`` at pressures ``p``; NaN when its
    segment differs. Loading/unloading: linear in pressure, extended with the end slopes
    up to EXTRAPOLATE_FRACTION of the segment's span. Hold: its angle at the same time
    since the hold began, moved to pressure ``p`` with the slope d angle/d p at the end
    of its previous segment (a specimen that holds at a higher pressure holds at a
    larger angle)."""
    m = seg == k
    nan = np.full(p.size, np.nan)
    if not np.any(m) or obs.direction[rows[m]][0] != d:
        return nan
    r = rows[m]
    if d == 0:
        t = _history(obs, rows)[m]
        y = np.interp(t_rel, t - t[0], obs.angle_deg[r], right=np.nan)
        if t.size < 2:
            y = np.full(p.size, obs.angle_deg[r][0])
        prev = rows[seg == k - 1]
        slope = _end_slope(obs, prev[-2:]) if prev.size >= 2 else 0.0
        return y + slope * (p - np.mean(obs.pressure_pa[r]))
    x, y = obs.pressure_pa[r], obs.angle_deg[r]
    order = np.argsort(x)
    x, y = x[order], y[order]
    if x.size < 2 or x[-1] - x[0] <= 0:
        return nan
    out = np.interp(p, x, y)
    lo_slope = (y[1] - y[0]) / max(x[1] - x[0], 1e-9)
    hi_slope = (y[-1] - y[-2]) / max(x[-1] - x[-2], 1e-9)
    out = np.where(p < x[0], y[0] + lo_slope * (p - x[0]), out)
    out = np.where(p > x[-1], y[-1] + hi_slope * (p - x[-1]), out)
    reach = EXTRAPOLATE_FRACTION * (x[-1] - x[0])
    return np.where((p >= x[0] - reach) & (p <= x[-1] + reach), out, np.nan)


def _end_slope(obs: Observations, rows: np.ndarray) -> float:
    dp = obs.pressure_pa[rows[1]] - obs.pressure_pa[rows[0]]
    return float((obs.angle_deg[rows[1]] - obs.angle_deg[rows[0]]) / dp) if abs(dp) > 1e-9 \
        else 0.0


def noise_floor(obs: Observations) -> NoiseFloor:
    sq, n_used, groups = 0.0, 0, 0
    per_curve: dict[int, list[float]] = {}   # per specimen
    spec = obs.curve_specimen()
    for g in np.unique(obs.group):
        curves = np.unique(obs.curve[obs.group == g])
        if np.unique(spec[curves]).size < 2:
            continue
        rows_of = {int(c): np.flatnonzero(obs.curve == c) for c in curves}
        seg_of = {c: segments(obs.direction[r]) for c, r in rows_of.items()}
        used_here = 0
        for c, rows in rows_of.items():
            seg = seg_of[c]
            t = _history(obs, rows)
            for k in np.unique(seg):
                m = seg == k
                d = obs.direction[rows[m]][0]
                p = obs.pressure_pa[rows[m]]
                t_rel = t[m] - t[m][0]
                o = _by_specimen([(spec[c2], _other_at(obs, rows2, seg_of[c2], d, k, p,
                                                        t_rel))
                                  for c2, rows2 in rows_of.items() if spec[c2] != spec[c]])
                share = _replicate_share(obs.angle_deg[rows[m]], o)
                if share is None:
                    continue
                term, n = share
                sq += term
                n_used += n
                acc = per_curve.setdefault(int(spec[c]), [0.0, 0])
                acc[0] += term
                acc[1] += n
                used_here += 1
        groups += used_here > 0
    if n_used >= MIN_READINGS:
        floor2 = sq / n_used
        means = np.array([a / n for a, n in per_curve.values() if n])
        rel = (0.5 * float(np.std(means, ddof=1)) / np.sqrt(means.size) / floor2
               if means.size >= 2 and floor2 > 0 else float("nan"))
        return NoiseFloor(float(np.sqrt(floor2)), n_used, "replicates", groups, rel)
    return _within_curve(obs)


def _within_curve(obs: Observations) -> NoiseFloor:
    """Reading scatter from second differences along each curve's history:
    d = y_i - (w y_{i-1} + (1 - w) y_{i+1}), Var d = sigma^2 (1 + w^2 + (1 - w)^2)."""
    sq, n = 0.0, 0
    for c in range(obs.n_curves):
        rows = np.flatnonzero(obs.curve == c)
        if rows.size < WITHIN_CURVE_MIN_POINTS:
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



def volume_floor(obs: Observations, y: np.ndarray) -> NoiseFloor | None:
    """How far a new specimen's reading ``y`` (its angle, deg, or its gauge pressure, Pa)
    scatters around its design's mean at the same injected volume: replicates (one design
    at one flow rate) compared in the same segment of their history at the same time since
    it began -- at one flow rate, the same volume; without time_s at the same volume --
    so what replicates share (the
    inlet's R Q, creep, a loop) is not scatter, while a specimen's own stiffness and
    geometry are. floor^2 = sum (y - mean_others)^2 / (1 + 1/k) / N as ``noise_floor``;
    ``rms_deg`` carries the floor in y's unit. None without injected volumes or
    replicates."""
    if not obs.has_volume:
        return None
    sq, n_used = 0.0, 0
    per_curve: dict[int, list[float]] = {}   # per specimen
    spec = obs.curve_specimen()
    for g in np.unique(obs.group):
        curves = np.unique(obs.curve[obs.group == g])
        if np.unique(spec[curves]).size < 2:
            continue
        cut = {}
        for c in curves:
            rows = np.flatnonzero(obs.curve == c)
            seg = segments(obs.direction[rows])
            cut[int(c)] = [(rows[seg == k], obs.direction[rows[seg == k]][0])
                           for k in range(int(seg.max()) + 1)]
        for c, parts in cut.items():
            for k, (r, d) in enumerate(parts):
                t = _along(obs, r, d)
                others = []
                for c2, parts2 in cut.items():
                    if spec[c2] == spec[c] or k >= len(parts2) or parts2[k][1] != d:
                        continue
                    r2 = parts2[k][0]
                    t2 = _along(obs, r2, d)
                    others.append((spec[c2], np.interp(t, t2, y[r2], left=np.nan,
                                                       right=np.nan)
                                   if t2.size > 1 else np.where(t == 0, y[r2][0], np.nan)))
                if not others:
                    continue
                o = _by_specimen(others)
                share = _replicate_share(y[r], o)
                if share is None:
                    continue
                term, n = share
                sq += term
                n_used += n
                acc = per_curve.setdefault(int(spec[c]), [0.0, 0])
                acc[0] += term
                acc[1] += n
    if n_used < MIN_READINGS or sq <= 0:
        return None
    floor2 = sq / n_used
    means = np.array([a / n for a, n in per_curve.values() if n])
    rel = (0.5 * float(np.std(means, ddof=1)) / np.sqrt(means.size) / floor2
           if means.size >= 2 else float("nan"))
    return NoiseFloor(float(np.sqrt(floor2)), n_used, "replicates", len(np.unique(obs.group)),
                      rel)


def _along(obs: Observations, rows: np.ndarray, direction: float) -> np.ndarray:
    """Where each reading of one segment of a curve's history lies, for comparing
    replicates: the time since the segment began (s); without time_s (a measured volume,
    _measured_volume.py) the injected volume (ul; negated while unloading, so that it
    rises) or, in a hold, the reading's place in it."""
    if obs.has_time:
        return obs.time_s[rows] - obs.time_s[rows][0]
    if direction == 0:
        return np.arange(rows.size, dtype=float)
    return obs.volume_ul[rows] * (1.0 if direction > 0 else -1.0)


def _by_specimen(others: list[tuple[int, np.ndarray]]) -> np.ndarray:
    """The other curves' values (rows: curves, columns: readings) with the runs of each
    specimen averaged into one row (NaN where none of its runs has a value)."""
    specimens = sorted({int(s) for s, _ in others})
    out = np.full((len(specimens), others[0][1].size if others else 0), np.nan)
    for i, s in enumerate(specimens):
        runs = np.array([v for s2, v in others if s2 == s])
        have = np.isfinite(runs)
        n = have.sum(axis=0)
        out[i] = np.where(n > 0, np.where(have, runs, 0.0).sum(axis=0) / np.maximum(n, 1),
                          np.nan)
    return out


def _replicate_share(y: np.ndarray, others: np.ndarray) -> tuple[float, int] | None:
    """One curve segment's share of the replicate scatter: sum over its readings of
    (y - mean of the other replicates there)^2 / (1 + 1/n), n the others that have a value
    there (so that the expectation is the scatter's variance per reading), and how many
    readings counted; None when no other replicate covers any of them."""
    n_others = np.sum(np.isfinite(others), axis=0)
    ok = n_others >= 1
    if not np.any(ok):
        return None
    diff = y[ok] - np.nanmean(others[:, ok], axis=0)
    return float(np.sum(diff**2 / (1.0 + 1.0 / n_others[ok]))), int(ok.sum())
