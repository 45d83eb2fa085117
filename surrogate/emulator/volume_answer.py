"""A design's answers by injected volume, read off its emulated curves (reduced ul, Pa).

Under volume control (a syringe pump) the angle and the chamber pressure are functions of
the injected volume V: the angle is read off the emulated V(theta) and its band off the
band's V(theta) curves, the pressure off the emulated p(theta) at the same angle
(``surrogate.volume_control.by_volume``, past a pressure maximum too). Nothing past the
FE's range: a volume above V(limit angle) gets NaN, as does an angle past the limit. The
one reading of these for a query of one design (``Emulator.predict_volume``,
``Emulator.inverse``) and for many at once (the design search's volume targets,
``many_designs.evaluate_designs_by_volume``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.emulator.node_curves import ANGLES0, floored_band
from surrogate.volume_control import VolumeAnswer, by_volume

# A fall of the emulated p(theta) below its running maximum counts as a pressure maximum
# from this relative size on: smaller wiggles (the shipped fit's largest is 2.5e-4) are far
# inside the band (a few per cent) and say nothing about the physics.
EMULATED_PRESSURE_DROP = 1e-3


@dataclass(frozen=True)
class AtVolumes:
    """At each reduced volume: |angle| (deg) with its band (NaN without ``band``), the
    reduced chamber pressure (Pa), all NaN past the FE's range (``past``); the range's
    end as a reduced volume (ul) and the curve's reading (pressure maximum) by volume."""

    angle_deg: np.ndarray
    lower_deg: np.ndarray
    upper_deg: np.ndarray
    pressure_red_pa: np.ndarray
    past: np.ndarray
    limit_volume_ul: float
    curve: VolumeAnswer


def at_volumes(v_red: np.ndarray, volume_band: tuple[np.ndarray, np.ndarray, np.ndarray],
               pressure_raw0: np.ndarray, limit_angle_deg: float, band: bool = True
               ) -> AtVolumes:
    """The answers at reduced volumes ``v_red`` (ul) from V(theta) on ANGLES0 (mean, the
    band's low and high curves, ``volume_band``), the mean p(theta) on ANGLES0 as emulated
    (``pressure_raw0``, reduced Pa, not made monotone: a maximum is read as one) and the
    FE range's end ``limit_angle_deg``."""
    vm, vl, vh = volume_band
    v_red = np.asarray(v_red, float)
    v_lim = float(np.interp(limit_angle_deg, ANGLES0, vm))
    past = v_red > v_lim * (1 + 1e-12)
    curve = by_volume(v_red, vm, pressure_raw0, ANGLES0, rel_drop=EMULATED_PRESSURE_DROP)
    angle = curve.angle_deg.copy()
    if band:
        lower, upper = floored_band(angle, np.interp(v_red, vh, ANGLES0),
                                    np.interp(v_red, vl, ANGLES0))
    else:
        lower, upper = np.full_like(angle, np.nan), np.full_like(angle, np.nan)
    pressure = curve.pressure_pa.copy()
    for a in (angle, lower, upper, pressure):
        a[past] = np.nan
    return AtVolumes(angle, lower, upper, pressure, past, v_lim, curve)


def volumes_at_angles(angle_deg: np.ndarray,
                      volume_band: tuple[np.ndarray, np.ndarray, np.ndarray],
                      limit_angle_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The reduced injected volume (ul) at each |angle| (deg), with the band's edges (the
    band's V(theta) curves); NaN past the FE range's end ``limit_angle_deg``."""
    a = np.asarray(angle_deg, float)
    past = a > limit_angle_deg + 1e-9
    return tuple(np.where(past, np.nan, np.interp(a, ANGLES0, c))  # type: ignore[return-value]
                 for c in volume_band)
