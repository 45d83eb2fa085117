"""A design's FE range: where its emulated curve ends (deg) and why.

The database curves end at the FE's stops (90 deg, the volume stop, the pressure stop)
or earlier at a Newton failure; a design's range ends at the first of: the FE's angle
stop, where its emulated injected volume reaches the FE's volume stop, the emulated end
of its FE curve (the range model) where nearby curves end early, the end of an
early-ended database curve within FAILED_RADIUS or the last volume of one that ended at a
Newton failure; and, per question, the FE's pressure stop (``pressure_stop_angle``).
"""

from __future__ import annotations

import numpy as np

from surrogate.emulator.pair_emulator import FAILED_RADIUS, NEAR_FAILED_RADIUS, PairEmulator
from surrogate.emulator.volume_curve import angle_at_volume_deg
from surrogate.predictor import FE_PRESSURE_STOP_PA

# A design this many times the box's size (W / 3 mm) or larger that reaches the FE's volume
# stop is told so, not that its balloon grows more than it bends: at W = 20 mm the curve
# ended at 0.2 deg for its k^3 = 296x volume, explained as a balloon that does not bend
# (the explorer audit of the thirty-seventh session).
VOLUME_STOP_SCALE = 1.5
# The emulated end of a design's FE curve (PairEmulator.range_model, a GP of where every
# database curve of the group ends: 90 deg, or earlier at the volume stop or a Newton
# failure) caps the range at its mean less RANGE_Z sd. The curves interpolated are the
# complete ones only; where most neighbours ended early (near the Ecoflex/Ecoflex balance,
# where the membrane balloons and the actuator hardly bends) the emulated V(theta) learnt
# nothing of them and did not reach the volume stop: a held-out design there whose FE
# stopped at 58 deg (500 ul) was answered to 88 deg, 30 deg off.
RANGE_Z = 1.0
# An emulated end at or above RANGE_COMPLETE_DEG is read as the FE's 90-deg angle stop,
# not as an early end: the range model's mean for a design among complete curves sits at
# 90 +/- its sd (median sd 6.3 deg), and mean - RANGE_Z sd cut 399 of the 415 complete FE
# curves of random designs at a median 83.8 deg, with a reason ("nearby curves end early")
# that was false. Of the 64 early-ended ones (range model means 19-81 deg, 5-95 %), none
# changes its cut at 85 (benchmarks/RESULTS.md, thirty-sixth session).
RANGE_COMPLETE_DEG = 85.0
# A database curve that passed a pressure maximum (``passed_pressure_maximum``) within
# FAILED_RADIUS names the range's end when its maximum is at most this far above the end
# found otherwise (deg): at the database design itself the range model's end, 1 sd short
# of the emulated one, lies a few hundredths of a degree below its maximum.
MAXIMUM_MATCH_DEG = 1.0


def end_volume_reason(volume_ul: float) -> str:
    """Why a design's range ends at ``volume_ul`` injected (whole actuator, ul): the
    volume at which early-ended database curves within FAILED_RADIUS ended
    (``PairEmulator.end_volume_cap_ul``, scaled to the design's size)."""
    return (f"the FE curves of nearby database designs ended at about {volume_ul:.0f} ul "
            "injected (at this design's size; a Newton failure, where the FE could go no "
            "further)")


def fe_range(pe: PairEmulator, u: np.ndarray, volume_red_ul: np.ndarray, length_scale: float,
             emulated_end: tuple[float, float | None] | None = None,
             failed_distances: np.ndarray | None = None) -> tuple[float, str]:
    """The FE's range for the design at unit coordinates ``u`` (deg) and why it ends
    there: the FE's angle stop; the angle at which the emulated injected volume
    ``volume_red_ul`` (reduced, on FINE_ANGLES_DEG) reaches the FE's volume stop; the
    emulated end of the design's FE curve less RANGE_Z sd (``pe.range_model``; pass
    ``pe.emulated_end_deg(u)`` as ``emulated_end`` when it is already known, its sd None
    when not: it is asked for here where it counts) where that
    end is below RANGE_COMPLETE_DEG or an early-ended database curve lies within
    NEAR_FAILED_RADIUS; the end of an early-ended database curve within FAILED_RADIUS
    (``pe.failed_distances(u)`` when already known); the angle at which the emulated
    volume reaches the last FE volume of such a curve that ended at a Newton failure
    (``PairEmulator.end_volume_cap_ul``: near such an end the emulated V(theta) is least sure;
    database design dad39d92, whose FE failed at 71.3 deg and 142.6 ul, was answered by
    volume to 199.5 ul)."""
    limit, reason = pe.fe_limit_angle_deg, pe.fe_stop_reason
    if failed_distances is None:
        failed_distances = pe.failed_distances(u)
    if pe.range_model is not None:
        mean_deg, sd_deg = (pe.emulated_end_deg(u) if emulated_end is None
                            else emulated_end)
        ends_early = mean_deg < RANGE_COMPLETE_DEG
        near = bool((failed_distances < NEAR_FAILED_RADIUS).any())
        if (ends_early or near) and sd_deg is None:
            mean_deg, sd_deg = pe.emulated_end_deg(u)
        end = float("inf") if sd_deg is None else max(mean_deg - RANGE_Z * sd_deg, 0.0)
        if (ends_early or near) and end < limit - 1.0:
            limit = end
            why = ("this design's FE curve is emulated to end early too, at "
                   f"{mean_deg:.0f} +/- {sd_deg:.0f} deg" if ends_early else
                   f"one lies within {NEAR_FAILED_RADIUS:g} of this design (unit box), "
                   f"and where this design's ends is uncertain ({mean_deg:.0f} +/- "
                   f"{sd_deg:.0f} deg)")
            reason = ("FE curves of database designs in this neighbourhood end early (the "
                      "volume stop, where the balloon grows more than the actuator "
                      f"bends, or a Newton failure): {why}; its range is taken to end "
                      f"{RANGE_Z:g} sd short of the emulated end")
    if pe.fe_max_volume_ul is not None:
        at_stop = angle_at_volume_deg(volume_red_ul, pe.fe_max_volume_ul / length_scale**3)
        if at_stop is not None and at_stop < limit:
            limit = at_stop
            reason = (f"the default FE stops at {pe.fe_max_volume_ul:g} ul injected "
                      "(SolverSettings.max_volume_ul), which this design's emulated "
                      "volume reaches there: " + (
                          "the balloon grows more than the actuator bends"
                          if length_scale <= VOLUME_STOP_SCALE else
                          f"a copy {length_scale:.3g}x the box's size in every length "
                          f"holds {length_scale**3:.3g}x its volume, so it reaches the "
                          "stop at a smaller angle (POST /v1/solve with a larger "
                          "max_volume_ul gives the rest)"))
    cap_ul = pe.end_volume_cap_ul(failed_distances)
    at_cap = None if cap_ul is None else angle_at_volume_deg(volume_red_ul, cap_ul)
    if at_cap is not None and at_cap < limit:
        limit = at_cap
        reason = (end_volume_reason(cap_ul * length_scale**3) + ", which this design's "
                  "emulated volume reaches there")
    if pe.failed:
        near = failed_distances < FAILED_RADIUS
        for i in np.flatnonzero(near):
            _, angle, why = pe.failed[i]
            if passed_pressure_maximum(why) and angle < limit + MAXIMUM_MATCH_DEG:
                limit = min(limit, float(angle))
                reason = pressure_maximum_reason(angle, why)
            elif angle < limit:
                limit = float(angle)
                reason = f"the FE curve of a nearby database design ended there: {why}"
    return limit, reason


def passed_pressure_maximum(reason: str) -> bool:
    """Whether a database curve counted among those that ended early (its rising
    branch, ``features.rising_branch``, ended before the FE's angle stop) went on to one
    of the FE's own angle or pressure stops: then its rising branch ended at a pressure
    maximum (a limit point), past which the FE, under volume control, continued."""
    return reason.startswith(("reached max_angle_deg", "reached max_pressure_pa"))


def pressure_maximum_reason(angle_deg: float, stop: str) -> str:
    """Why a range ends at the pressure maximum of a nearby database curve that went on
    past it (``passed_pressure_maximum``): database design 031e5d18, whose FE curve has
    its maximum at 45.6 deg and goes on to 90 deg, was told its curve ends early "(the
    volume stop ... or a Newton failure)", or that it "ended there: reached
    max_angle_deg = 90.0" (the audit of the forty-first session)."""
    return (f"the FE curve of a nearby database design has a pressure maximum (a limit "
            f"point) at {angle_deg:.1f} deg and goes on past it under volume control "
            f"({stop}); the emulator reads every FE curve up to its pressure maximum "
            "only, so it gives no number past it: an FE solve (POST /v1/solve) gives "
            "this design's own curve there")


def pressure_stop_angle(limit_deg: float, angles_deg: np.ndarray,
                        pressure_red_pa: np.ndarray, pressure_scale: float) -> float | None:
    """The angle (deg) where a design's emulated mean p(theta) (``pressure_red_pa`` at
    ``angles_deg``, reduced: the membrane at s = 1, non-decreasing) reaches the FE's
    pressure stop, FE_PRESSURE_STOP_PA / ``pressure_scale`` reduced, when that comes
    before the range's end ``limit_deg``; None when it does not. The memoised curve is
    shared by every pressure scale of a reduced design, so the stop is applied per
    question: layers 50x their presets were answered to 105843 Pa in Python while the
    default FE stops at 20 kPa."""
    stop_red = FE_PRESSURE_STOP_PA / pressure_scale
    if float(np.interp(limit_deg, angles_deg, pressure_red_pa)) <= stop_red:
        return None
    return float(np.interp(stop_red, pressure_red_pa, angles_deg))
