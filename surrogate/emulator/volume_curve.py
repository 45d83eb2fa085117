"""The emulated injected volume V(theta) of a design, made to rise as the FE's volumes do.

Reduced: the whole actuator's injected volume (ul) at W = 3 mm; a design k times the
box's size holds k^3 times it.
"""

from __future__ import annotations

import numpy as np

from surrogate.emulator.features import FINE_ANGLES_DEG
from surrogate.emulator.node_curves import _B_ANGLE, ANGLES0, _with_origin

# The injected volume's shape: on every complete free-tip FE curve of the balanced
# database (1526 curves, 2026-12-04) the local exponent d log V / d log theta stays above
# 0.41 from 20 deg on (1 % quantile of each curve's minimum 0.46-0.48, median 0.60).
VOLUME_EXPONENT_FLOOR = 0.4
VOLUME_FLOOR_FROM_DEG = 20.0
_VOLUME_FLOOR_STEP = np.concatenate(([0.0], np.where(
    FINE_ANGLES_DEG[1:] > VOLUME_FLOOR_FROM_DEG,
    VOLUME_EXPONENT_FLOOR * np.diff(np.log(FINE_ANGLES_DEG)), 0.0)))
_VOLUME_FLOOR = np.cumsum(_VOLUME_FLOOR_STEP)


def volume_shape(v: np.ndarray) -> np.ndarray:
    """An emulated V(theta) on FINE_ANGLES_DEG (ul, > 0; rows of a 2-D ``v`` are designs)
    made to rise as the FE's do: never falling, and from VOLUME_FLOOR_FROM_DEG on at least
    as theta^VOLUME_EXPONENT_FLOOR from any earlier point (log V - floor is made
    non-decreasing, floor the cumulative minimum rise). Where the GP's log(V/theta) falls
    too steeply at high angles (it did near early-ended Ecoflex/Ecoflex curves, volume
    flat from 66 to 89 deg where the FE's rose 45 -> 67 ul), the running maximum alone
    left a plateau, and the angle read at a volume on it jumped by 20 deg or more."""
    lv = np.log(v) - _VOLUME_FLOOR
    return np.exp(np.maximum.accumulate(lv, axis=-1) + _VOLUME_FLOOR)


def angle_at_volume_deg(volume_red_ul: np.ndarray, v_red: float) -> float | None:
    """The angle (deg) at which an emulated V(theta) (``volume_red_ul``: reduced ul on
    FINE_ANGLES_DEG, non-decreasing, ``volume_shape``) reaches the reduced volume
    ``v_red`` (ul), linear between the fine angles as a query by volume reads it (so that
    the range's end by volume is ``v_red`` itself); None where it does not."""
    v = np.asarray(volume_red_ul, float)
    if v[-1] < v_red:
        return None
    return float(np.interp(v_red, _with_origin(v), ANGLES0))


def emulated_volume_ul(log_v_nodes: np.ndarray) -> np.ndarray:
    """The emulated V(theta) on FINE_ANGLES_DEG (reduced ul; rows of a 2-D input are
    designs) from the volume nodes' log(V / theta): the natural spline through them, made
    to rise as the FE volumes do (``volume_shape``)."""
    return volume_shape(FINE_ANGLES_DEG * np.exp(log_v_nodes @ _B_ANGLE.T))

