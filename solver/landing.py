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
         corrections: int = LANDING_CORRECTIONS) -> Point | None:
    """The converged state at the load interpolated to the middle of the landing window
    [limit, limit + tolerance], then at most ``corrections`` more at secant loads inside
    the bracket, until one lands in the window. Returns the state nearest the stop at or
    past it (which may still lie past the window), or None if none converged at or past
    the stop. None also when ``above`` is already in the window.

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
    for _ in range(1 + corrections):
        point = converge(interpolated_load(aim, below, above))
        if point is None:
            break
        if point.value >= limit and (best is None or point.value < best.value):
            best = point
        if limit <= point.value <= limit + tolerance:
            break
        if point.value < aim:
            below = point
        else:
            above = point
    return best


def volume_load_at(injected_ul: float, injected_volume_ul: Callable[[float], float],
                   volume0_mm3: float) -> float:
    """The cavity volume (the model's, mm^3: the load under volume control) at which the
    injected volume is ``injected_ul`` (ul): ``injected_volume_ul`` of a model is affine
    in its cavity volume (the change times the copies of the model in the whole
    actuator), so two of its values give its inverse."""
    at_rest = injected_volume_ul(volume0_mm3)
    per_mm3 = injected_volume_ul(volume0_mm3 + 1.0) - at_rest
    return volume0_mm3 + (injected_ul - at_rest) / per_mm3
