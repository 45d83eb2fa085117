"""How each reading was taken: loading, unloading or hold, from the pressure sequence.

Labs record a curve in time (or file) order; the pressure's change from the previous
reading says what the pump did: rising = loading (fluid in, direction +1), falling =
unloading (withdrawn, -1), pressure and angle unchanged = hold (pump stopped, 0). The
first reading takes the direction of the next interval; a drop into a flat stretch is the
start of a hold (the gauge loses the inlet's R Q when the pump stops). The noise floor,
the time effects' identifiability and the inlet pressure drop (R Q x direction) use it.
"""

from __future__ import annotations

import numpy as np

HOLD_FRACTION = 0.01  # a constant-flow inflation near its pressure maximum still rises
HOLD_MIN_PA = 8.0     # faster (1 % of the range per reading at 1 s, 2.5 ul/s)
#: holds below this fraction of a curve's top pressure are the actuator at rest, not holds
REST_FRACTION = 0.1


def directions(curve: np.ndarray, pressure_pa: np.ndarray, angle_deg: np.ndarray
               ) -> np.ndarray:
    """+1 / -1 / 0 per row; rows sorted by curve, then history. A reading is classified
    by the pressure's change from the previous one (the pump's state since then): within
    HOLD_FRACTION of the curve's pressure range (at least HOLD_MIN_PA, above a pressure
    sensor's noise) it is a hold. A drop followed by a flat interval is the step into a
    hold (the inlet's R Q vanishing when the pump stops), not unloading. Pressure alone
    decides: angles are noisier, and creep moves them during a hold."""
    out = np.zeros(pressure_pa.size)
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        p = pressure_pa[rows]
        tol = max(HOLD_FRACTION * float(np.ptp(p)), HOLD_MIN_PA)
        dp = np.diff(p)
        flat = np.abs(dp) <= tol
        back = np.where(flat, 0.0, np.sign(dp))
        fwd_flat = np.append(flat[1:], False)
        d = np.where((back < 0) & fwd_flat, 0.0, back)
        out[rows[1:]] = d
        out[rows[0]] = d[0] if d.size else 0.0
    return out


def history_traits(curve: np.ndarray, pressure_pa: np.ndarray, direction: np.ndarray
                   ) -> dict[str, int]:
    """Counts of loading, unloading and hold readings (holds at rest not counted)."""
    top = np.zeros(int(curve.max()) + 1)
    np.maximum.at(top, curve, pressure_pa)
    hold = (direction == 0) & (pressure_pa > REST_FRACTION * top[curve])
    return {"loading": int(np.sum(direction > 0)), "unloading": int(np.sum(direction < 0)),
            "hold": int(np.sum(hold))}
