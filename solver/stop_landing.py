"""A solve's stops, and its last volume step redone by FE steps to land on the stop it met
first (the search over the load: solver/landing.py).

The stops are the settings' ``max_angle_deg`` (deg, on the angle's magnitude),
``max_pressure_pa`` (Pa) and ``max_volume_ul`` (ul, whole actuator). The volume stop needs
no landing: the last volume step is capped at the cavity volume (mm^3, the model's) where
the injected volume reaches it, plus the Newton tolerance on the volume, so that the
state converged there is at or past it. A stop the user chose (not the defaults', where
the database's curves end) is landed with the Illinois corrections too, and its reason
says where a curve ended off it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.discrete import ActuatorModel
from solver.hermite_predictor import PREDICTOR_POINTS, State, predictor
from solver.landing import (
    STOPS,
    USER_STOP_CORRECTIONS,
    Point,
    interpolated_load,
    land,
    landing_tolerance,
    stop_values,
    volume_load_at,
)
from solver.newton import Converged, StepFailed, mixed_newton_step
from solver.settings import SolverSettings

DEFAULT_SETTINGS = SolverSettings()   # its stops are the database's (solver/landing.py)


@dataclass(frozen=True)
class Stops:
    """A solve's stops: each stop's limit (deg, Pa, ul), whether the user chose it, and
    the cavity volume (mm^3) the last volume step is capped at (inf under pressure
    control)."""

    limits: dict[str, float]
    user_stop: dict[str, bool]
    volume_cap_mm3: float


def solve_stops(settings: SolverSettings, model: ActuatorModel) -> Stops:
    """The stops of a solve of ``model`` with ``settings``."""
    limits = {name: getattr(settings, name) for name in STOPS}
    user_stop = {name: limits[name] != getattr(DEFAULT_SETTINGS, name) for name in STOPS}
    volume_cap_mm3 = (volume_load_at(settings.max_volume_ul, model.injected_volume_ul,
                                     model.volume0_mm3)
                      + settings.newton_tol * model.volume0_mm3
                      if settings.control == "volume" else np.inf)
    return Stops(limits, user_stop, volume_cap_mm3)


def land_on_stop(model: ActuatorModel, settings: SolverSettings, backend: str, stops: Stops,
                 reached: list[str], was: dict[str, float], now: dict[str, float],
                 before: tuple, after_load: float, history: list[State]
                 ) -> tuple[str, Converged, int] | None:
    """The last converged step (at the cavity volume ``after_load``, its stop values
    ``now``) reached the stops ``reached``: the converged state on the stop met first
    from ``before`` (the previous converged state (u, q, p, evaluation), its stop values
    ``was``), by solver/landing.py, as (stop, state, its Newton solves); None where the
    step needs no landing (it is on the volume stop, or ``before`` was past a stop too)
    or none converged nearer the stop than the step itself (the curve then ends on it,
    as before). Each landing step starts from the Hermite predictor through the last
    converged states ``history`` (the step past the stop among them: an interpolation),
    else from ``before``."""
    limits = stops.limits
    if any(was[name] >= limits[name] for name in reached):
        return None
    before_load = before[3].volume_mm3
    loads = {name: stops.volume_cap_mm3 if name == "max_volume_ul" else interpolated_load(
        limits[name], Point(before_load, was[name]), Point(after_load, now[name]))
        for name in reached}
    stop = min(reached, key=lambda name: loads[name])     # met first along the step
    if stop == "max_volume_ul":
        return None
    tried = list(history)
    solves = 0

    def converge(load: float) -> Point | None:
        nonlocal solves
        model.timings["landing_steps"] = model.timings.get("landing_steps", 0) + 1
        guess = predictor(tried, load)
        for u0, q0, p0, start in ([] if guess is None else [(*guess, None)]) + [before]:
            try:
                out = mixed_newton_step(model, u0, q0, p0, settings, load, None,
                                        backend, start=start)
            except (StepFailed, FloatingPointError):
                continue
            solves += out.iterations
            tried.append(State(load, out.u, out.q, out.pressure_pa, out.rate))
            del tried[:-PREDICTOR_POINTS]
            values = stop_values(model.end_face_kinematics(out.u)[0], out.pressure_pa,
                                 model.injected_volume_ul(out.evaluation.volume_mm3))
            return Point(load, values[stop], out)
        return None

    limit = limits[stop]
    best = land(limit, landing_tolerance(stop, limit), Point(before_load, was[stop]),
                Point(after_load, now[stop]), converge,
                further=USER_STOP_CORRECTIONS if stops.user_stop[stop] else 0)
    if best is None or abs(best.value - limit) >= abs(now[stop] - limit):
        return None
    return stop, best.state, solves
