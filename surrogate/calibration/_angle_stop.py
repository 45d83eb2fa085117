"""An angle sensor at the end of its range: readings pinned at one value while the pump
keeps injecting and the gauge keeps rising.

A bending actuator's angle rises with its chamber pressure all along a loading (the FE
curves, the paper's exponential): near the top of a curve the bend per Pa is at least
what it was a reading below. A sensor that stops at its range -- an encoder or a
protractor at its end, a marker leaving the camera's frame, a tracker clipped to its full
scale -- reads one value from there on while the gauge still rises; so does a bend
stopped by something the actuator touches. Neither is the actuator's response. Read as
the actuator's, the stopped readings looked like the pump stopping a reading early: the
history read off the readings (_history.py) took the last loading reading for a hold,
and every later injected volume was an interval off (benchmarks/lab_rig_sets.py N45, a
sensor stopping at 60 deg while the actuator bends to 75 deg: unflagged before
2026-12-07; N52, one reading exactly 45.0 from its stop on, fitted as a membrane 10 %
stiffer).

From the data alone. Each curve's bend is signed so that it bends positive; its level is
the median of its readings within ``TOL_DEG`` of its largest bend, and a reading within
``TOL_DEG`` of the level is at it. Replicates read with one pump program (one design and
flow rate, the same reading times) are read together, at the first interval whose two
readings are at the level in every replicate: a stop where the pump still injected over
it -- the gauge rose in every replicate, on average by at least ``PACE_SHARE`` of its
mean rise per reading over the two readings below, a pace of at least ``PACE_MIN`` of
the pressure there (at a flat top, near a curve's pressure maximum, one gauge's noise in
a hold rises as much, and nothing is read), or the pump's log says "load" -- while the
bend the curves' own slope over the interval below gives for that rise exceeds what they
bent by at least ``DEFICIT_DEG`` and twice over. The last interval at the level, the
pump already withdrawing, is not read: a pressure relaxing in a hold falls there too.

The stop is the sensor's, one value: every curve bending the same way whose level lies
within ``TOL_DEG`` of it has its readings at the level (loading, hold or unloading: there
the sensor cannot tell) kept out of the fit (_loop.py), with a warning naming angle_deg
(the report's ``angle_stop``); their pressures and times still count for the pump's
history, whose intervals there are read by the gauge alone (_history.py).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

#: readings within this of a curve's level are at it (3 x a camera's 0.7 deg noise)
TOL_DEG = 2.0
#: the pump's pace: the gauge's mean rise per reading over the two readings below the
#: level must be at least this fraction of the pressure there (a 1.5 % gauge's noise
#: moves a difference of two readings by 2 %, the mean of six by 0.9 %: at a flat top,
#: near the curve's pressure maximum, the gauge cannot tell the pump running)
PACE_MIN = 0.05
#: and the gauge's mean rise over the stopped interval at least this share of that pace
#: (the pump still injecting; a hold's gauge does not rise, a pump stopping within the
#: interval leaves the bend below the level)
PACE_SHARE = 0.5
#: the bend missing over the interval, on the replicates' average (deg)
DEFICIT_DEG = 3.0


def _bend(angle_deg: np.ndarray) -> tuple[float, np.ndarray]:
    """The sign of the curve's bend and its angles signed to bend positive."""
    sign = 1.0 if angle_deg[np.argmax(np.abs(angle_deg))] >= 0 else -1.0
    return sign, sign * angle_deg


def _level(bend: np.ndarray) -> float:
    return float(np.median(bend[bend >= np.max(bend) - TOL_DEG]))


def _replicate_sets(curve: np.ndarray, group: np.ndarray, time_s: np.ndarray) -> list:
    """Curves read with one pump program: one group, the same number of readings and
    (with time_s) the same times within a tenth of their interval."""
    timed = bool(np.all(np.isfinite(time_s)))
    sets: dict[tuple, list[np.ndarray]] = {}
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        key: tuple = (int(group[rows[0]]), rows.size)
        if timed and rows.size > 1:
            step = max(float(np.median(np.diff(time_s[rows]))), 1e-9)
            key += tuple(np.round(time_s[rows] / step * 10).astype(int) // 10)
        sets.setdefault(key, []).append(rows)
    return list(sets.values())


def _pumped_interval(k: int, curves: list[np.ndarray], bends: list,
                     pressure_pa: np.ndarray, pump: np.ndarray | None) -> dict | None:
    """The evidence of interval ``k`` (readings k, k + 1, at the level in every
    replicate), or None: the pump still injecting over it (the pump's log says "load" in
    every replicate, or the gauge rises in every one, on average by ``PACE_SHARE`` of
    its pace over the two intervals below, a pace of at least ``PACE_MIN`` of the
    pressure), while the bend misses at least ``DEFICIT_DEG`` of, and more than half of,
    what its slope over the interval below gives for that rise."""
    if k < 2:
        return None
    p = [pressure_pa[r] for r in curves]
    dp = np.array([q[k + 1] - q[k] for q in p])
    slopes = []
    for b, q in zip(bends, p, strict=True):
        db, dq = b[k] - b[k - 1], q[k] - q[k - 1]
        if db <= 0 or dq <= 0:
            return None
        slopes.append(db / dq)
    if pump is not None:
        injecting = bool(np.all(pump[[r[k + 1] for r in curves]] > 0))
    else:
        pace = float(np.mean([(q[k] - q[k - 2]) / 2 for q in p]))
        at = float(np.mean([q[k] for q in p]))
        injecting = bool(np.all(dp > 0) and pace >= PACE_MIN * at
                         and float(np.mean(dp)) >= PACE_SHARE * pace)
    expected = float(np.mean(np.array(slopes) * np.maximum(dp, 0.0)))
    bent = float(np.mean([b[k + 1] - b[k] for b in bends]))
    if not injecting or expected - bent < DEFICIT_DEG or bent > 0.5 * expected:
        return None
    return {"rise_pa": float(np.mean(dp)), "missing_deg": expected - bent}


def _stopped_interval(curves: list[np.ndarray], pressure_pa: np.ndarray,
                      angle_deg: np.ndarray, pump: np.ndarray | None) -> dict | None:
    """The evidence that one set of replicates reads a stop, or None: its levels agree
    and the first interval at the level in every replicate is one the pump injected
    over (``_pumped_interval``). (The last interval at the level, the pump already
    withdrawing, is not read: a pressure relaxing in a hold falls there too.)"""
    bends, levels, at = [], [], []
    for rows in curves:
        sign, b = _bend(angle_deg[rows])
        lv = _level(b)
        bends.append(b)
        levels.append(sign * lv)
        at.append(b >= lv - TOL_DEG)
    if np.ptp(levels) > 2 * TOL_DEG or np.unique(np.sign(levels)).size > 1:
        return None
    both = np.flatnonzero(np.all([m[1:] & m[:-1] for m in at], axis=0))
    if both.size == 0:
        return None
    ev = _pumped_interval(int(both[0]), curves, bends, pressure_pa, pump)
    return None if ev is None else {"level_deg": float(np.median(levels)), **ev}


@dataclass(frozen=True)
class AngleStop:
    """A stop of the angle readings found in the data (``find``): its level (deg, signed
    as the data's angles), the curves whose readings reach it and, per row, the readings
    at it (``pinned``; ``readings`` of them when found), with the evidence: the gauge's
    mean rise over the stopped interval and the bend the curves' slope below gives for
    it and the readings lack."""

    level_deg: float
    curves: tuple[str, ...]
    pinned: np.ndarray
    readings: int
    rise_pa: float
    missing_deg: float

    @classmethod
    def find(cls, curve: np.ndarray, curve_ids: tuple[str, ...], group: np.ndarray,
             time_s: np.ndarray, pressure_pa: np.ndarray, angle_deg: np.ndarray,
             pump: np.ndarray | None = None) -> AngleStop | None:
        """The stop the readings show (rows sorted by curve, then history; ``pump`` the
        pump's logged state per reading, when logged), or None."""
        if not (np.all(np.isfinite(angle_deg)) and np.all(np.isfinite(pressure_pa))):
            return None
        found = [ev for rows in _replicate_sets(curve, group, time_s)
                 if min(r.size for r in rows) >= 4
                 for ev in [_stopped_interval(rows, pressure_pa, angle_deg, pump)] if ev]
        if not found:
            return None
        level = float(np.median([ev["level_deg"] for ev in found]))
        pinned = np.zeros(curve.size, bool)
        names = []
        for c in np.unique(curve):
            rows = np.flatnonzero(curve == c)
            sign, b = _bend(angle_deg[rows])
            if sign * level > 0 and abs(sign * _level(b) - level) <= TOL_DEG:
                pinned[rows] = b >= sign * level - TOL_DEG
                names.append(curve_ids[c])
        return cls(level, tuple(names), pinned, int(pinned.sum()),
                   float(np.median([ev["rise_pa"] for ev in found])),
                   float(np.median([ev["missing_deg"] for ev in found])))

    def rows(self, keep: np.ndarray) -> AngleStop:
        """The stop with its per-row mask taken at the rows ``keep``."""
        return replace(self, pinned=self.pinned[np.asarray(keep, bool)])

    def warning(self) -> str:
        """The warning naming angle_deg: what the readings show, what is done, and what
        to measure."""
        return (f"angle_deg: the angle readings stop at {self.level_deg:.1f} deg "
                f"({len(self.curves)} curves) while the pump still injects and the gauge "
                f"still rises ({self.rise_pa:.0f} Pa over a reading where the bend just "
                f"below would add {self.missing_deg:.1f} deg): that is the end of the angle "
                "sensor's range (or an obstacle stopping the bend), not the actuator's "
                f"response; the {self.readings} readings at that level are left out of the "
                "fit (a sensor whose range covers the whole bend would calibrate the top "
                "of the curve)")

    def as_dict(self) -> dict:
        """The report's ``angle_stop``."""
        return {"level_deg": self.level_deg, "curves": list(self.curves),
                "readings_left_out": self.readings, "gauge_rise_pa": self.rise_pa,
                "bend_missing_deg": self.missing_deg}
