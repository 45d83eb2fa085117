"""Answers near the stiffness balance, read off the group's balance model.

Where a soft group's sign model cannot tell which way a design bends (within SIGN_MARGIN
of the balance), or where the design's FE curve ends at the volume stop short of 90 deg,
the answer is the balance model's (``balance``: the signed angle and log pressure at
fixed injected volumes), by pressure, by volume and backwards (the inverse), up to the
FE's range there, flagged ``near_stiffness_balance``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from solver.design import Design
from solver.design_space import BoxPoint
from solver.errors import InputError
from solver.settings import SolverSettings
from surrogate.band_level import z_value
from surrogate.emulator.balance import (
    VOLUME_NODES_UL,
    BalanceModel,
    first_reach,
    turn_back_deg,
    turns_back,
)
from surrogate.emulator.fe_range import end_volume_reason
from surrogate.emulator.force_answer import blocked_force, force_flags
from surrogate.emulator.node_curves import floored_band
from surrogate.emulator.vector_gp import MEANS_ONLY
from surrogate.predictor import (
    FE_PRESSURE_STOP_PA,
    InversePrediction,
    Prediction,
    band_within_fe,
    pressure_stop_reason,
)

if TYPE_CHECKING:
    from surrogate.emulator.emulator import Emulator

SIGN_MARGIN = 0.5         # |sign model| below this: too near the stiffness balance
# The balance model (surrogate.emulator.balance) also answers where it says the FE curve
# ends at the volume stop: its angle at the last volume node plus BALANCE_TOP_Z of its sd
# below BALANCE_TOP_DEG. On the 121 Ecoflex/Ecoflex FE curves of random designs (band
# calibration and held-out sets) with a direction, the 33 so chosen were within the
# per-curve target on 23 by volume and 23 by pressure, against 8 and 21 answered by the
# per-direction curve GPs (benchmarks/RESULTS.md, twenty-fifth session; 70-90 deg chose
# the same curves, the largest 77.9).
BALANCE_TOP_DEG = 80.0
BALANCE_TOP_Z = 2.0
# ... unless the direction's range model emulates the FE curve to reach this (a database
# curve that reached 90 deg at 115 ul was answered 35 deg off by the balance model, which
# only knows curves that end at the volume stop; of the 460 designs of the database and
# the random-design sets it chose, that was the one emulated to end at 89 deg or later)
BALANCE_COMPLETE_DEG = 89.0
# The balance model answers up to this share of the FE's volume stop (its curves end past
# it, at the first step beyond) or its last node, whichever is smaller.
BALANCE_VOLUME_MARGIN = 0.96


def bending_direction(m: np.ndarray) -> np.ndarray:
    """+1 / -1 from a sign model's mean; 0 within SIGN_MARGIN of the balance, where the
    FE data do not tell which way the design bends."""
    return np.where(np.abs(m) < SIGN_MARGIN, 0.0, np.sign(m))


def balance_message(designs: int) -> str:
    """What an answer near the stiffness balance is read from (its first message)."""
    return ("this design sits near the balance of the two layers' stiffness, where both "
            "balloon alike and the FE curve ends at the volume stop short of 90 deg (either "
            "way round): answered by the signed angle at fixed injected volumes, "
            f"interpolated across the balance from {designs} FE curves that end there "
            "(docs/surrogate.md); ")


TURN_FLAG = "curve_turns_back"


def add_turn_back(nodes: tuple, point: BoxPoint, validity: dict) -> None:
    """Add the flag TURN_FLAG and its message to ``validity`` (its lists "flags" and
    "messages") where the balance model's curve from ``nodes`` (``BalanceModel.nodes``)
    turns back: its |angle| falls by more than TURN_BACK_DEG after its peak."""
    angle, _, p_nodes = nodes
    if not turns_back(angle):
        return
    k = int(np.argmax(np.abs(angle)))
    validity["flags"].append(TURN_FLAG)
    validity["messages"].append(
        f"the emulated curve turns back: its angle peaks at {angle[k]:.1f} deg near "
        f"{VOLUME_NODES_UL[k] * point.length_scale**3:.0f} ul "
        f"({p_nodes[k] * point.pressure_scale:.0f} Pa) and falls by "
        f"{turn_back_deg(angle):.1f} deg by the last volume node. Near the stiffness "
        "balance an FE curve can turn back (the membrane's balloon takes over the body's "
        "bending), but few database curves do, and where the emulated curve turns back "
        "the emulator's error is several times that elsewhere, whether or not the FE's "
        "does; its band is widened to the turning curves' own calibration "
        "(docs/surrogate.md). An FE solve (POST /v1/solve) gives this design's own curve")


def balance_answers(emulator: Emulator, group: str, model: BalanceModel, u: np.ndarray
                    ) -> bool:
    """Whether ``model`` answers for the design at unit coordinates ``u`` of ``group``
    (``Emulator.balance_model_for``)."""
    m = emulator.sign_models[group].predict(u, variance_of=MEANS_ONLY)[0][:1]
    sign = bending_direction(m)[0]
    if sign == 0.0:
        return True
    top = model.top_deg(u, BALANCE_TOP_Z)
    if top >= BALANCE_TOP_DEG:
        return False
    # the balance model knows no curve that reaches 90 deg before the volume stop: where
    # the direction's range model says the FE curve is complete, it is the curve GPs'
    pe = emulator.pairs.get(group + ("+" if sign > 0 else "-"))
    if pe is not None and pe.ends_short_of_volume_stop_at(u):
        return False
    if pe is not None and pe.range_model is not None:
        if pe.emulated_end_deg(u)[0] >= BALANCE_COMPLETE_DEG:
            return False
    return True


def balance_answer(emulator: Emulator, design: Design, point: BoxPoint, axis: str,
                   x: np.ndarray, level: float) -> Prediction:
    """The answer at the stiffness balance (``balance``): the signed angle with its band
    at each pressure (``axis`` "pressure", Pa) or injected volume ("volume", ul), up to
    the volume stop of the FE curves there; the blocked-tip force of the per-direction
    force model where the design has a direction, none at the balance itself."""
    model = emulator.balance_models[point.group]
    z = z_value(level)
    ls3 = point.length_scale**3
    nodes = model.nodes(point.coordinates())
    if axis == "pressure":
        angle, lower, upper, v_red = model.by_pressure(nodes, x / point.pressure_scale, z)
        pressure, volume = x.copy(), v_red * ls3
    else:
        v_red = x / ls3
        angle, lower, upper, p_red = model.by_volume(nodes, v_red, z)
        pressure, volume = p_red * point.pressure_scale, x.copy()
    lower, upper = floored_band(angle, lower, upper)
    v_limit, stop, pressure_stopped, limit_pa, limit_angle = balance_limits(
        emulator, model, nodes, point, z)
    past = v_red > v_limit * (1 + 1e-12)
    for a in (angle, lower, upper, pressure if axis == "volume" else volume):
        a[past] = np.nan
    force = pair = None
    try:        # a design with a direction keeps the blocked-tip force it had
        pair = emulator.curve_band(point, z, volume_band=False)
        force = blocked_force(emulator._memo,  # type: ignore[attr-defined]
                              *pair[:2], point, pressure / point.pressure_scale, z)
        for f in force or ():
            f[past] = np.nan
    except InputError:
        pass    # at the balance itself: no direction, no force model
    flags = ["near_stiffness_balance"]
    messages = [balance_message(model.designs)
                + ("no force is emulated where the direction is undecided; "
                   if force is None else "the blocked-tip force is the force model's "
                   "for the direction the design bends; ")
                + "an FE solve (POST /v1/solve) gives this design's own curve"]
    if force is not None and pair is not None:
        force_flags(*pair, point, np.where(past, np.nan, pressure), force, flags, messages,
                    f"{axis}(s)")
    if past.any():
        flags.insert(0, "past_fe_range")
        if pressure_stopped:
            flags.insert(1, "past_fe_pressure_stop")
        what = (f"pressure(s) above {limit_pa:.0f} Pa" if axis == "pressure" else
                f"volume(s) above {v_limit * ls3:.1f} ul")
        messages.insert(0, f"{int(past.sum())} {what} are past the FE's range for this "
                           f"design, which ends at {limit_angle:.1f} deg ({stop}): no "
                           "angle is given there")
    # in_domain: the design is in the box (a design outside is refused); the points
    # past the range have their own flag
    validity: dict[str, object] = {
        "in_domain": True, "flags": flags, "messages": messages,
        "fe_limit_pa": limit_pa, "fe_limit_angle_deg": limit_angle,
        "fe_stop_reason": stop, "fe_limit_volume_ul": v_limit * ls3}
    add_turn_back(nodes, point, validity)
    # the curves here end at the volume stop, short of the FE's angle stop: no band past it
    lower, upper = band_within_fe(lower, upper, SolverSettings().max_angle_deg, validity)
    return emulator._prediction(design, point, pressure, (angle, lower, upper), level,
                                validity, force, volume)


def balance_limits(emulator: Emulator, model: BalanceModel, nodes: tuple, point: BoxPoint,
                   z: float) -> tuple[float, str, bool, float, float]:
    """The FE's range of a design the balance model answers: (its end as a reduced
    injected volume in ul, why it ends there, whether that is the FE's pressure stop,
    the chamber pressure in Pa and the signed angle in deg there)."""
    v_stop = min(float(VOLUME_NODES_UL[-1]),
                 BALANCE_VOLUME_MARGIN * SolverSettings().max_volume_ul
                 / point.length_scale**3)
    # the group's early-ended curves (the same in both directions' pair emulators)
    pe = emulator.pairs.get(point.group + "+") or emulator.pairs.get(point.group + "-")
    cap_ul = (None if pe is None else
              pe.end_volume_cap_ul(pe.failed_distances(point.coordinates())))
    cap_reason = None
    if cap_ul is not None and cap_ul < v_stop:
        v_stop = cap_ul
        cap_reason = end_volume_reason(cap_ul * point.length_scale**3)
    v_limit, stop, pressure_stopped = balance_range_end(
        model, nodes, v_stop, z, point.pressure_scale, cap_reason)
    at_limit = model.by_volume(nodes, np.array([v_limit]), z)
    top = SolverSettings().max_angle_deg
    return (v_limit, stop, pressure_stopped, float(at_limit[3][0]) * point.pressure_scale,
            float(np.clip(at_limit[0][0], -top, top)))


def balance_inverse(emulator: Emulator, design: Design, point: BoxPoint,
                    angles: np.ndarray, level: float) -> InversePrediction:
    """The inverse near the stiffness balance, from the balance model that answers by
    pressure and by volume there (``BalanceModel.volumes_for``): for each signed
    angle the chamber pressure (Pa) and injected volume (ul) where the model's angle
    first reaches it, with their bands; none where it is not reached within the FE's
    range (the volume stop, or the angle stop). The per-direction GPs' inverse, used
    here until 2026-12-06, gave 28.5 and 125 ul for 10 and 30 deg where the FE needs
    21.1 and 85.4 ul, and the answer by those volumes read 13.8 and 32.7 deg (an
    audit of the thirty-seventh session)."""
    model = emulator.balance_models[point.group]
    z = z_value(level)
    ls3, s = point.length_scale**3, point.pressure_scale
    nodes = model.nodes(point.coordinates())
    v_limit, stop, pressure_stopped, limit_pa, limit_angle = balance_limits(
        emulator, model, nodes, point, z)
    volumes, pressures = model.volumes_for(nodes, angles, v_limit, z)
    validity: dict[str, object] = {
        "in_domain": True, "flags": ["near_stiffness_balance"],
        "messages": [balance_message(model.designs) + "the injected volume and chamber "
                     "pressure are where its angle first reaches each target; an FE "
                     "solve (POST /v1/solve) gives this design's own curve"],
        "fe_limit_pa": limit_pa, "fe_limit_angle_deg": limit_angle,
        "fe_stop_reason": stop, "fe_limit_volume_ul": v_limit * ls3}
    add_turn_back(nodes, point, validity)
    unreached = np.isnan(volumes[0])
    if unreached.any():
        validity["flags"].insert(0, "past_fe_range")
        if pressure_stopped:
            validity["flags"].insert(1, "past_fe_pressure_stop")
        validity["messages"].insert(
            0, f"no pressure for {int(unreached.sum())} angle(s) not reached within the "
               f"FE's range, which ends at {limit_angle:.1f} deg for this design ({stop})")
    return InversePrediction(design=design, angle_deg=angles, pressure_pa=pressures[0] * s,
                             lower_pa=pressures[1] * s, upper_pa=pressures[2] * s,
                             level=level, validity=validity, model=emulator.name,
                             form="emulator", provenance=dict(emulator.provenance),
                             volume_ul=volumes[0] * ls3, volume_lower_ul=volumes[1] * ls3,
                             volume_upper_ul=volumes[2] * ls3)


def balance_range_end(model: BalanceModel, nodes: tuple, v_limit: float, z: float,
                      pressure_scale: float, volume_reason: str | None = None
                      ) -> tuple[float, str, bool]:
    """Where the FE's range ends for a design the balance model answers (reduced
    volume, ul) and why: the volume stop, or the FE's angle stop or its pressure stop
    (FE_PRESSURE_STOP_PA, at ``pressure_scale``) where the balance model's mean
    reaches one first. Answered past 90 deg, a design near the balance with a stiff
    body read 122 and 135 deg at 200 and 480 ul, its band cut to [90, 90] (an audit
    of the thirty-fifth session). The third item: whether it is the pressure stop.
    ``volume_reason``: why the range ends at ``v_limit`` when that is not the volume
    stop (``end_volume_reason``)."""
    top = SolverSettings().max_angle_deg
    grid = np.linspace(0.0, v_limit, 241)[1:]
    angle, _, _, p_red = model.by_volume(nodes, grid, z)
    ends = []   # (volume, why, pressure stop?) of each stop reached before the volume stop
    for x, stop, why in (
            (np.abs(angle), top, f"the FE's angle stop ({top:g} deg, "
             "SolverSettings.max_angle_deg), which the balance model's curve reaches "
             "before the volume stop"),
            (p_red * pressure_scale, FE_PRESSURE_STOP_PA, None)):
        v_end = float(first_reach(grid, x, np.array([stop]))[0])
        if np.isfinite(v_end):
            ends.append((v_end, why or pressure_stop_reason(
                float(np.nanmax(p_red)) * pressure_scale), why is None))
    if not ends:
        return v_limit, volume_reason or (
            f"the FE's volume stop ({SolverSettings().max_volume_ul:g} ul, "
            "SolverSettings.max_volume_ul), where the FE curves near the balance end"
        ), False
    return min(ends)
