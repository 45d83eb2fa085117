"""The validity of an answer by pressure or by volume: its flags and messages.

``past_fe_range`` (and ``past_fe_pressure_stop``) where asked past the design's FE range,
``near_early_ended_fe_curves`` within NEAR_FAILED_RADIUS of a database curve that ended
early, ``band_undercovers_random_designs`` where the group's band covered too little of
the FE curves of random designs (the second calibration, ``random_calibration``),
``high_membrane_stretch`` at answered angles past which the design's emulated membrane
stretch enters the range where FE curves often end in Newton failures (``stretch_hazard``),
and the force's flags (``force_answer.force_flags``). The FE's range itself: ``fe_limit_pa``,
``fe_limit_angle_deg``, ``fe_stop_reason``.
"""

from __future__ import annotations

import numpy as np

from solver.design_space import BoxPoint
from surrogate.emulator.curve_band import CurveBand
from surrogate.emulator.features import FINE_ANGLES_DEG
from surrogate.emulator.force_answer import force_flags
from surrogate.emulator.pair_emulator import NEAR_FAILED_RADIUS, PairEmulator
from surrogate.emulator.stretch_hazard import FLAG

# A design whose group and side (near or far from early-ended curves) had its band cover
# less than this share of the points of FE curves of random designs, after the band's
# second calibration, on at least UNDERCOVER_MIN_POINTS of them, is flagged
# ``band_undercovers_random_designs`` (the honest range is 0.90-0.98).
UNDERCOVER_LEVEL = 0.90
UNDERCOVER_MIN_POINTS = 40


def random_design_coverage(report: dict, pair: str, axis: str, near: bool) -> dict | None:
    """How well the bands of group ``pair`` (``axis`` "pressure" or "volume", designs near
    an early-ended curve or not) covered the FE curves of random designs after the second
    calibration, by the fit's ``report`` (``Emulator.report``): {"coverage", "points",
    "curves"}, or None (files before 2026-12-04, or no such points)."""
    cal = report.get("random_design_calibration") or {}
    cell = ((cal.get("group_coverage_after") or {}).get(pair) or {}).get(axis) or {}
    found = cell.get("near" if near else "far")
    return found if found and found.get("coverage") is not None else None


def undercover(report: dict, pe: PairEmulator, cb: CurveBand, axis: str
               ) -> tuple[str, str] | None:
    """The flag and message when this design's group and side covered too little."""
    near = cb.failed_distance < NEAR_FAILED_RADIUS
    cell = random_design_coverage(report, pe.pair, axis, near)
    if (cell is None or cell["points"] < UNDERCOVER_MIN_POINTS
            or cell["coverage"] >= UNDERCOVER_LEVEL):
        return None
    where = "near" if near else "away from"
    return ("band_undercovers_random_designs",
            f"on FE curves of random designs of this group {where} curves that ended "
            f"early ({cell['curves']} curves, {cell['points']} points), the band by "
            f"{axis} covered only {100 * cell['coverage']:.0f} % of the FE's points, "
            "against the 95 % it states: the emulator is off by more than its band "
            "says here; an FE solve (POST /v1/solve) gives this design's own curve")


def stretch_flag(pe: PairEmulator, cb: CurveBand, point: BoxPoint,
                 answered_deg: np.ndarray, validity: dict) -> None:
    """Add the flag ``high_membrane_stretch``, its message and where it starts
    (``high_stretch_from_deg``, signed as the design's angles, and ``high_stretch_from_pa``)
    to ``validity`` where answered angles ``answered_deg`` (unsigned deg; NaN: not
    answered) reach the angle from which this design's emulated membrane stretch passes
    the hazard stretch (``stretch_hazard``)."""
    onset = cb.stretch_onset_deg
    a = np.asarray(answered_deg, float)
    hit = np.isfinite(a) & (a >= onset)
    if pe.stretch_hazard is None or not hit.any():
        return
    onset_pa = float(np.interp(onset, FINE_ANGLES_DEG, cb.pressure_pa)) * point.pressure_scale
    validity["flags"].append(FLAG)
    validity["messages"].append(pe.stretch_hazard.message(onset, onset_pa, int(hit.sum()),
                                                          pe.pair.rstrip("+-")))
    validity["high_stretch_from_deg"] = pe.sign * onset
    validity["high_stretch_from_pa"] = onset_pa


def answer_validity(report: dict, pe: PairEmulator, cb: CurveBand, point: BoxPoint,
                    p: np.ndarray, past: np.ndarray, force: object, axis: str = "pressure",
                    answered_deg: np.ndarray | None = None) -> dict[str, object]:
    """The validity of an answer at chamber pressures ``p`` (Pa; ``past`` where past
    the FE's range) by ``axis`` ("pressure" or "volume"), ``force`` the force answered
    (None: no force model), ``report`` the fit's (``Emulator.report``), ``answered_deg``
    the answered angles (unsigned deg, NaN where none: the stretch flag)."""
    flags: list[str] = []
    messages: list[str] = []
    fe_limit_pa = cb.limit_pressure_pa * point.pressure_scale
    limit_deg = pe.sign * cb.limit_angle_deg        # signed, as the design's angles
    if past.any():
        flags.append("past_fe_range")
        messages.append(
            f"{int(past.sum())} pressure(s) above {fe_limit_pa:.0f} Pa are past the FE's "
            f"range for this design, which ends at {limit_deg:.1f} deg "
            f"({cb.stop_reason}): no angle is given there; an FE solve of this "
            "design (POST /v1/solve; its max_angle_deg and max_volume_ul can be raised) "
            "tells where its curve really ends")
        if cb.pressure_stopped:
            flags.append("past_fe_pressure_stop")
    near = cb.failed_distance
    if near < NEAR_FAILED_RADIUS:
        flags.append("near_early_ended_fe_curves")
        messages.append(
            f"a database design {near:.2f} away (unit cube; {NEAR_FAILED_RADIUS:g} or "
            "less counts as near) has an FE curve that ended early (the volume stop, "
            "where the balloon grows more than the actuator bends, or a Newton "
            "failure): there the FE's response changes abruptly and the emulator is "
            "least reliable, its error on random designs two to three times that "
            "elsewhere and its band widened to match (docs/surrogate.md); an FE solve "
            "(POST /v1/solve) gives this design's own curve")
    under = undercover(report, pe, cb, axis)
    if under is not None:
        flags.append(under[0])
        messages.append(under[1])
    if force is not None:
        force_flags(pe, cb, point, p, force, flags, messages, f"{axis}(s)")
    # in_domain: the design is in the box (a design outside is refused before this);
    # the points past the FE's range have their own flag, past_fe_range
    validity = {"in_domain": True, "flags": flags, "messages": messages,
                "fe_limit_pa": fe_limit_pa, "fe_limit_angle_deg": limit_deg,
                "fe_stop_reason": cb.stop_reason}
    if answered_deg is not None:
        stretch_flag(pe, cb, point, answered_deg, validity)
    return validity
