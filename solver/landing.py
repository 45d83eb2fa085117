"""Landing a volume-controlled curve on its stop instead of one load step past it.

The stepping aims at ~8 deg of bending per step, so the first converged step at or past
a stop (``max_angle_deg`` on the angle's magnitude -- a reversed pair bends to negative
angles --, ``max_pressure_pa``, ``max_volume_ul``) generally lies past it. The stepping
replaces that step by one from the previous converged state to the load (the cavity
volume, mm^3) at which the stop is met: the stop's quantity interpolated linearly in the
load between the two states, then at most ``LANDING_CORRECTIONS`` secant corrections
inside the bracket (a state below the stop, one past it) while the landed value lies short
of the stop or more than ``landing_tolerance`` past it. The volume stop needs no search: the
stepping caps the volume load at it (the injected volume is affine in the cavity volume),
as pressure control caps the pressure load.

Those two corrections are a regula falsi: on a convex curve (the angle rises as about the
cube of the volume near rest) every one lands short and the end past the stop never
moves, so a user's stop of 0.1 deg ended at 0.19 deg and the curve said "reached". A stop
other than the defaults (``SolverSettings``: 90 deg, 20 kPa; the database's curves end
there, and their landing is left exactly as it was) gets up to ``USER_STOP_CORRECTIONS``
more, by the Illinois rule (the end kept twice in a row has its distance to the aim
halved in the interpolation: superlinear on a convex curve too, and never outside the
bracket). A curve that still ends off its stop says where it ended (``stop_reason``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

# The stops, in the order the reason of a step past several of them names them.
STOPS = ("max_angle_deg", "max_pressure_pa", "max_volume_ul")
LANDING_RELATIVE_TOL = 1e-3     # a landing within 0.1 % of the stop ...
LANDING_ANGLE_TOL_DEG = 0.01    # ... and, for the angle, within 0.01 deg, is on it
LANDING_CORRECTIONS = 2         # secant corrections after the interpolated landing
USER_STOP_CORRECTIONS = 10      # Illinois corrections after those, for a user's stop


def stop_values(angle_deg: float, pressure_pa: float, volume_ul: float) -> dict[str, float]:
    """Each stop's quantity at a converged state: the bending angle's magnitude (deg),
    the cavity pressure (Pa) and the injected volume (ul)."""
    return {"max_angle_deg": abs(angle_deg), "max_pressure_pa": pressure_pa,
            "max_volume_ul": volume_ul}


def stops_reached(limits: dict[str, float], values: dict[str, float],
                  at_volume_cap: bool = False) -> list[str]:
    """The stops a converged state is at or past, in the order of ``STOPS``.
    ``at_volume_cap``: the state was converged at the volume load capped at the volume
    stop (its injected volume then equals the stop within the Newton tolerance only)."""
    return [name for name in STOPS
            if values[name] >= limits[name] or (name == "max_volume_ul" and at_volume_cap)]


def landing_tolerance(name: str, limit: float) -> float:
    """How far past the stop ``limit`` a landed value may lie, in the stop's unit: 0.1 %
    of the stop, and no more than 0.01 deg for the angle. A landing never ends short of
    the stop: a curve that reached ``max_angle_deg`` = 90 reaches 90 deg (the emulator
    reads every default curve to there)."""
    tolerance = LANDING_RELATIVE_TOL * abs(limit)
    return min(tolerance, LANDING_ANGLE_TOL_DEG) if name == "max_angle_deg" else tolerance


@dataclass(frozen=True)
class Point:
    """A converged state as the landing sees it: its load (cavity volume, mm^3) and the
    value of the stop's quantity there (deg, Pa or ul); ``state``: the caller's."""

    load: float
    value: float
    state: Any = None


def interpolated_load(limit: float, below: Point, above: Point) -> float:
    """The load at which the stop's quantity, linear in the load between a state below
    the stop and one at or past it, equals ``limit``."""
    share = (limit - below.value) / (above.value - below.value)
    return below.load + share * (above.load - below.load)


def land(limit: float, tolerance: float, below: Point, above: Point,
         converge: Callable[[float], Point | None],
         corrections: int = LANDING_CORRECTIONS, further: int = 0) -> Point | None:
    """The converged state at the load interpolated to the middle of the landing window
    [limit, limit + tolerance], then at most ``corrections`` more at secant loads inside
    the bracket, then at most ``further`` more at Illinois loads, until one lands in the
    window. Returns the state nearest the stop at or past it (which may still lie past
    the window), or None if none converged at or past the stop. None also when ``above``
    is already in the window.

    ``converge(load)``: the converged state at that load (a Point), or None. ``below``
    (value < limit) and ``above`` (value >= limit) bracket the window's middle; a landed
    state replaces the end on its side, so every load tried lies between two converged
    states on either side of it (also where the quantity is not monotone in the load,
    e.g. the pressure past a maximum within the bracket).
    """
    if above.value - limit <= tolerance:
        return None
    aim = limit + 0.5 * tolerance
    best = None
    # the Illinois weights of the two ends' distances to the aim (1: the secant's)
    weight = {"below": 1.0, "above": 1.0}
    kept = ""                   # the end the last step kept
    for attempt in range(1 + corrections + further):
        illinois = attempt > corrections
        point = converge(_weighted_load(aim, below, above, weight) if illinois
                         else interpolated_load(aim, below, above))
        if point is None:
            break
        if point.value >= limit and (best is None or point.value < best.value):
            best = point
        if limit <= point.value <= limit + tolerance:
            break
        side = "below" if point.value < aim else "above"
        if side == "below":
            below = point
        else:
            above = point
        # an end kept twice in a row has its weight halved (read by the Illinois steps)
        other = "above" if side == "below" else "below"
        weight[side], weight[other] = 1.0, (0.5 * weight[other] if kept == other else 1.0)
        kept = other
    return best


def _weighted_load(aim: float, below: Point, above: Point, weight: dict[str, float]) -> float:
    """The secant load between the ends with their distances to ``aim`` weighted (the
    Illinois rule's halving): always strictly inside the bracket."""
    f_below = weight["below"] * (below.value - aim)
    f_above = weight["above"] * (above.value - aim)
    share = -f_below / (f_above - f_below)
    return below.load + share * (above.load - below.load)


def on_stop(name: str, limit: float, value: float) -> bool:
    """Whether the stop's quantity ``value`` at a curve's last point is on the stop:
    at or past it by at most ``landing_tolerance``."""
    return limit <= value <= limit + landing_tolerance(name, limit)


def stop_reason(name: str, limit: float, value: float, user_stop: bool) -> str:
    """A curve's reason for ending at the stop ``name``: "reached <name> = <limit>", and
    for a user's stop not landed on (``on_stop``), where the curve ended (in the stop's
    unit) -- it still begins "reached <name>", as the database's readers take it. The
    defaults' words are left as they were (their curves are the database's)."""
    reason = f"reached {name} = {limit}"
    if user_stop and not on_stop(name, limit, value):
        unit = {"max_angle_deg": "deg", "max_pressure_pa": "Pa", "max_volume_ul": "ul"}[name]
        reason += (f", ended at {value:.6g} {unit}: past it by more than the landing's "
                   f"{landing_tolerance(name, limit):.3g} {unit}")
    return reason


def volume_load_at(injected_ul: float, injected_volume_ul: Callable[[float], float],
                   volume0_mm3: float) -> float:
    """The cavity volume (the model's, mm^3: the load under volume control) at which the
    injected volume is ``injected_ul`` (ul): ``injected_volume_ul`` of a model is affine
    in its cavity volume (the change times the copies of the model in the whole
    actuator), so two of its values give its inverse."""
    at_rest = injected_volume_ul(volume0_mm3)
    per_mm3 = injected_volume_ul(volume0_mm3 + 1.0) - at_rest
    return volume0_mm3 + (injected_ul - at_rest) / per_mm3
