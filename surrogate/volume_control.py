"""Answers by injected volume on a tabulated curve (pure; ul, Pa, deg).

Under volume control (a syringe pump) the injected volume is what is set and grows
monotonically, so angle and pressure are functions of it even where the pressure has a
maximum (a limit point: past it the pressure falls while the volume still rises; under
pressure control the actuator would snap through there). ``by_volume`` interpolates the
curve's own angle and pressure columns linearly in volume, and says where the asked
volumes lie past the curve's pressure maximum or past its end. The pump's flow limits
(``MIN_FLOW_UL_S``..``MAX_FLOW_UL_S``, defined in solver/settings.py with the solver's
own; time = volume / flow from the undeformed state) are the one table the service's pump
view, the design search's time targets and measured data read.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.errors import InputError
from solver.settings import MAX_FLOW_UL_S, MIN_FLOW_UL_S  # the one table (re-exported)

FLOW_RANGE = f"{MIN_FLOW_UL_S:g} <= flow_ul_s <= {MAX_FLOW_UL_S:g} ul/s"
MAX_TIME_S = 1e5           # the longest pump time asked (times_s, a search's time_s), s
LONGEST_TIME_FLAG = "past_longest_pump_time"


def cut_past_longest_time(values: dict, validity: dict, fields: tuple[str, ...],
                          flow_ul_s: float, what: str = "point(s)",
                          kept: str = "volume_ul is the fluid needed") -> None:
    """In place: no time (s) in ``values[field]`` (lists) above MAX_TIME_S, the longest
    pump time the service takes (``times_s``), flag ``past_longest_pump_time`` in
    ``validity`` (its ``flags`` and ``messages``): at 1e-6 ul/s the inverse answered 45 deg
    after 2.4e7 s, a time the forward answer by time refuses. The volume is kept (``kept``
    says where); each bound of a band is cut alone. The one cut of the forward and inverse
    answers (service/pump.py) and of the design search's pump targets (pump_targets.py)."""
    cut = 0
    for name in fields:
        times = values.get(name)
        if times is None:
            continue
        over = [t is not None and t > MAX_TIME_S for t in times]
        values[name] = [None if o else t for t, o in zip(times, over, strict=True)]
        cut = max(cut, sum(over))
    if not cut:
        return
    validity["flags"].append(LONGEST_TIME_FLAG)
    validity["messages"].append(
        f"{cut} {what} take longer than {MAX_TIME_S:g} s at {flow_ul_s:g} ul/s, the longest "
        f"pump time the service answers (times_s <= {MAX_TIME_S:g} s): no time is given "
        f"there; {kept}")


@dataclass(frozen=True)
class VolumeAnswer:
    """At each asked volume: angle (deg) and pressure (Pa), NaN past the curve's end.

    past_end           the volume is above the curve's last volume
    past_maximum       the volume is above the volume at the pressure maximum (the
                       pressure falls from there on); all False without a maximum
    maximum_pressure_pa, maximum_volume_ul, maximum_angle_deg
                       the pressure maximum (None without one)
    """

    angle_deg: np.ndarray
    pressure_pa: np.ndarray
    past_end: np.ndarray
    past_maximum: np.ndarray
    maximum_pressure_pa: float | None
    maximum_volume_ul: float | None
    maximum_angle_deg: float | None


def pressure_maximum_index(pressure_pa: np.ndarray, rel_drop: float = 0.0) -> int:
    """The index of the curve's first pressure maximum: the largest pressure before the
    first point that falls more than ``rel_drop`` (relative) below the running maximum;
    -1 when the pressure never falls that far."""
    p = np.asarray(pressure_pa, float)
    run = np.maximum.accumulate(p)
    falls = np.flatnonzero(p < run * (1.0 - rel_drop) - 1e-12 * np.abs(run))
    if falls.size == 0:
        return -1
    return int(np.argmax(p[:falls[0]]))


def by_volume(volumes_ul: np.ndarray, curve_volume_ul: np.ndarray,
              curve_pressure_pa: np.ndarray, curve_angle_deg: np.ndarray,
              rel_drop: float = 0.0) -> VolumeAnswer:
    """Angle and pressure at ``volumes_ul`` on the curve (its volume non-decreasing),
    linear in volume; the pressure maximum found as in ``pressure_maximum_index``."""
    v = np.asarray(volumes_ul, float)
    cv = np.asarray(curve_volume_ul, float)
    cp = np.asarray(curve_pressure_pa, float)
    ca = np.asarray(curve_angle_deg, float)
    if cv.size < 2 or np.any(np.diff(cv) < 0):
        raise InputError("volume_ul", "the curve's volume is not non-decreasing: it was not "
                         "solved under volume control", "a volume-controlled curve")
    past_end = v > cv[-1] * (1 + 1e-12)
    angle = np.interp(v, cv, ca)
    pressure = np.interp(v, cv, cp)
    angle[past_end] = np.nan
    pressure[past_end] = np.nan
    k = pressure_maximum_index(cp, rel_drop)
    if k < 0:
        return VolumeAnswer(angle, pressure, past_end, np.zeros(v.shape, bool), None, None,
                            None)
    return VolumeAnswer(angle, pressure, past_end, (v > cv[k]) & ~past_end, float(cp[k]),
                        float(cv[k]), float(ca[k]))
