"""How each reading was taken: loading, unloading or hold, from the pressure sequence.

Labs record a curve in time (or file) order; the pressure's change from the previous
reading says what the pump did: rising = loading (fluid in, direction +1), falling =
unloading (withdrawn, -1), pressure and angle unchanged = hold (pump stopped, 0). The
first reading takes the direction of the next interval; a drop into a flat stretch is the
start of a hold (the gauge loses the inlet's R Q when the pump stops). The noise floor,
the time effects' identifiability and the inlet pressure drop (R Q x direction) use it,
and so does the injected volume (``injected_volume_ul``: the syringe pump's volume, from
time, flow rate and direction).
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


def injected_volume_ul(curve: np.ndarray, time_s: np.ndarray, flow_ul_s: np.ndarray,
                       direction: np.ndarray) -> np.ndarray:
    """The volume the pump has put into the chamber at each reading (ul): V_0 = Q d t_0,
    V_k = V_(k-1) + Q d_k (t_k - t_(k-1)) along each curve (rows sorted by curve, then
    time; d the pump's state since the previous reading). ``time_s`` counts from the start
    of the pump with the chamber at rest (empty of injected fluid); NaN without time or
    flow. An incompressible fluid and stiff tubing are assumed: the pump's volume is the
    chamber's."""
    out = np.full(time_s.size, np.nan)
    if not (np.all(np.isfinite(time_s)) and np.all(np.isfinite(flow_ul_s))):
        return out
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        t = time_s[rows]
        dt = np.diff(np.concatenate([[0.0], t]))
        out[rows] = np.maximum(np.cumsum(flow_ul_s[rows] * direction[rows] * dt), 0.0)
    return out
