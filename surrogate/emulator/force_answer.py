"""The blocked-tip force a query answers (mN, with its band), and why it is withheld.

The force model (``PairEmulator.force``, ``features.force_angle_feature``) is read at the
design's reduced pressures and scaled by the membrane's stiffness scale times the square
of the length scale; no force is given where its band is wider than FORCE_BAND_LIMIT x the
force (flag ``force_band_too_wide``) or past the force's range (``force_past_fe_range``).
"""

from __future__ import annotations

import numpy as np

from solver.design_space import BoxPoint
from surrogate.emulator.curve_band import CurveBand
from surrogate.emulator.design_memo import DesignMemo
from surrogate.emulator.node_curves import ANGLES0, _with_origin
from surrogate.emulator.pair_emulator import PairEmulator
from surrogate.predictor import one_signed

FORCE_BAND_LIMIT = 2.0     # widest force band answered, relative to the force
# A force band narrower than this (mN, full width) is answered whatever its relative width:
# the blocked tip's first steps (0.01 uN at 25 Pa on the standard design, its band 0.2 uN
# wide: the initial reaction's sign is uncertain) are far below what a lab's force sensor
# resolves, and withholding them only raised the flag on every design.
FORCE_BAND_FLOOR_MN = 2e-3


def force_backed(force: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Where a force answer is given: its band (mN) within FORCE_BAND_LIMIT x the force,
    or narrower than FORCE_BAND_FLOOR_MN. A NaN force or band (no force answer) is not
    backed."""
    with np.errstate(invalid="ignore"):
        width = np.asarray(upper, float) - np.asarray(lower, float)
        relative = width <= FORCE_BAND_LIMIT * np.abs(np.asarray(force, float)) + 1e-9
        return relative | (width <= FORCE_BAND_FLOOR_MN)


def blocked_force(memo: DesignMemo, pe: PairEmulator, cb: CurveBand, point: BoxPoint,
                  p_red: np.ndarray, z: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Blocked-tip force (mN) with its band: F = p x (F/p emulated at the pressure
    nodes, linear between them), F scaling with s_membrane x length_scale^2. The force
    GP's mean and variance at the design are kept in ``memo`` (the emulator's)."""
    if pe.force is None:
        return None
    mean, var = memo.get_or_make(
        ("force", pe.pair, cb.coordinates.tobytes()),
        lambda: pe.force.predict(cb.coordinates))
    sd = np.sqrt(var) * pe.force_sd_scales(cb.blocked_mean_pa)
    scale = point.pressure_scale * point.length_scale**2
    past = p_red > pe.force_end_pa(cb.limit_pressure_pa, cb.blocked_end_pa) * (1 + 1e-12)
    pm, pl, pu = cb.force_reference or (cb.pressure_pa, cb.pressure_lower_pa,
                                        cb.pressure_upper_pa)
    angle = np.interp(p_red, _with_origin(pm), ANGLES0)
    angle_hi = np.interp(p_red, _with_origin(pl), ANGLES0)
    angle_lo = np.interp(p_red, _with_origin(pu), ANGLES0)
    out = [scale * f for f in pe.force_reduced(mean, sd, cb.node_mean, p_red, angle,
                                                angle_lo, angle_hi, z)]
    for f in out:
        f[past] = np.nan
    out = list(one_signed(*out, pe.sign))   # the blocked tip pushes the way it bends
    lo, hi = out[1], out[2]
    # no force where its band is wider than FORCE_BAND_LIMIT x the force itself:
    # the group's few blocked-tip designs do not back a number there
    unbacked = ~force_backed(out[0], lo, hi) & np.isfinite(out[0])
    return (np.where(unbacked, np.nan, out[0]), np.where(unbacked, np.nan, lo),
            np.where(unbacked, np.nan, hi))


def force_flags(pe: PairEmulator, cb: CurveBand, point: BoxPoint, p: np.ndarray,
                force: tuple, flags: list[str], messages: list[str],
                points: str = "pressure(s)") -> None:
    """Append why the force is withheld at some of the chamber pressures ``p`` (Pa;
    NaN where the angle itself is past the range): its band too wide within the
    force's range, or past that range (``force_past_fe_range``). ``points`` names the
    points as the question asked them ("pressure(s)", "volume(s)")."""
    f_end = pe.force_end_pa(cb.limit_pressure_pa, cb.blocked_end_pa)
    f_lim = f_end * point.pressure_scale
    within = p <= f_lim * (1 + 1e-12)        # False at NaN: past the angle's range
    unbacked = np.isnan(force[0]) & within
    if unbacked.any():
        flags.append("force_band_too_wide")
        messages.append(f"no force at {int(unbacked.sum())} {points}: its band "
                        f"is wider than {FORCE_BAND_LIMIT:g} x the force there (too "
                        "few blocked-tip FE curves near this design; an FE solve "
                        "with tip = blocked gives it)")
    if not within.all():
        flags.append("force_past_fe_range")
        if f_end >= cb.blocked_end_pa * (1 - 1e-12):
            why = pe.blocked_range.reason(  # type: ignore[union-attr]
                cb.coordinates, cb.blocked_mean_pa, cb.blocked_end_pa,
                point.pressure_scale)
        elif f_end >= pe.force_limit_pa * (1 - 1e-12):
            why = "the end of the blocked-tip FE curves"
        else:
            why = ("the end of this design's free-tip range (the force is "
                   "emulated as its ratio to the free tip's angle at the same "
                   "pressure)")
        messages.append(f"force is given up to {f_lim:.0f} Pa, {why}")
