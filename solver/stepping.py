"""Quasi-static inflation of the actuator: adaptive load stepping with Newton.

Two controls:

* pressure: each step prescribes p; Newton solves K du = -R.
* volume (a fluid cavity, as in Abaqus or FEBio): each step prescribes the
  injected volume; the pressure is an extra unknown of a bordered Newton system
  (solver/newton.py). It passes pressure plateaus and maxima, as the syringe-pump
  experiment does.

The Newton iterate is the mixed u-q pair (element pressures q as unknowns, condensed
per element; solver/assembly.py): with the penalty form, the spurious second-order
dilatation of a large rotating predictor step, times the bulk modulus, made the
tangent indefinite and forced ~2.5 degree steps; the mixed iterate takes the full
target step (benchmarks/RESULTS.md).

Each step is converged by Newton on that iterate, with chord updates near the solution
(solver/newton.py: ``mixed_newton_step``), from the Hermite predictor through the last
three converged states and their path tangents (solver/hermite_predictor.py; the Euler
predictor along the undeformed state's tangent for the first step).
A step whose extrapolated start fails
is retried from the converged state before it is cut back; a failed step is cut back by
half; the step grows when Newton converges quickly and shrinks when the angle increment
is large, aiming at ~8 degrees and at most ~150 Pa (or 8 % of the
pressure, if more) per step (so that the curve is resolved where the angle is small
and the pressure rises fast; solver/step_size.py).
A step that cannot converge after the cut-backs ends the curve with status
"failed" and the reason. With ``follow_stable_branch`` the curve leaves a branch that is
unstable at constant volume (solver/branch_following.py).

The curve ends on its stop, not one step past it. Under pressure control the last step's
pressure is capped at max_pressure_pa, under volume control its volume at max_volume_ul;
and a volume step that converged past max_angle_deg or max_pressure_pa is replaced by one
from the previous converged state to the volume at which the stop is met
(solver/stop_landing.py, solver/landing.py: interpolated, then up to two secant
corrections, and for a stop other than the defaults' up to ten Illinois corrections; the
landed state at or past the stop by at most 0.1 % of it and 0.01 deg). Only the curve's
last point moves; where no landing converges nearer the stop, or the step switched
branch, the step past the stop ends the curve, as before the landing (a user's stop's
reason then says where it ended).

The loop (``inflate_model``) reads as these steps: ``start_at_rest``, then per step
``next_load``, ``converge_step`` (on failure ``cut_back``, and ``switch_past_fold``),
``accept_step``, ``switch_past_bifurcation``, the next step's size, ``end_on_stop``; the
state they share between steps is one ``PathState``, what they hold fixed one
``Run``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from threadpoolctl import ThreadpoolController

from solver.branch_following import FAILURES_BEFORE_SWITCH, near_bifurcation, try_switch
from solver.curve import Curve
from solver.curve_columns import CurveColumns
from solver.design import Design
from solver.discrete import ActuatorModel, Evaluation
from solver.hermite_predictor import PREDICTOR_POINTS, State, path_rate, predictor
from solver.landing import stop_reason, stop_values, stops_reached
from solver.mesh import MeshDivisions
from solver.newton import (
    Converged,
    StepFailed,
    counted_factorisation,
    counted_solve,
    mixed_newton_step,
)
from solver.settings import SolverSettings
from solver.step_size import MIN_CUTBACK, first_step, step_factor
from solver.stop_landing import Stops, land_on_stop, solve_stops


def solve(design: Design, settings: SolverSettings | None = None,
          on_step: Callable[[dict], None] | None = None, backend: str = "auto",
          divisions: MeshDivisions | None = None,
          follow_stable_branch: bool = False) -> Curve:
    """Inflate ``design`` until a stop criterion; return the curve.

    ``follow_stable_branch`` (volume control): where the state first becomes unstable
    at constant volume (a bifurcation, solver/stability.py), locate it and continue on
    the stable branch by continuation in the unstable mode's amplitude; where a step
    keeps failing (``FAILURES_BEFORE_SWITCH``: a fold in volume), pass the fold by arc
    length (solver/branching.py); the curve records the step in
    ``branch_switch_index`` (the first switch only). Off by default: the database's
    curves follow the primary branch and flag the instability
    (``volume_control_negative_eigenvalues``).

    Raises InputError for invalid input only; a solve that fails returns a Curve
    with status "failed" and the reason.
    """
    return inflate(design, settings, on_step, backend, divisions=divisions,
                   follow_stable_branch=follow_stable_branch)[0]


def inflate(design: Design, settings: SolverSettings | None = None,
            on_step: Callable[[dict], None] | None = None, backend: str = "auto",
            debug: bool = False, divisions: MeshDivisions | None = None,
            follow_stable_branch: bool = False) -> tuple[Curve, ActuatorModel, np.ndarray]:
    """Like ``solve``, also returning the discrete model and the last converged
    displacement (free dofs), for field output (VTK). ``divisions``: an explicit level-0
    mesh resolution for convergence studies (records know only the named ones); None takes
    ``settings.mesh_divisions``.

    numpy's OpenBLAS is held to one thread meanwhile: its idle threads spin and take
    the cores from MKL PARDISO's, which does the parallel work (benchmarks/RESULTS.md).
    """
    settings = (settings or SolverSettings()).validated()
    design = design.validated()
    with ThreadpoolController().select(internal_api="openblas").limit(limits=1):
        return _inflate(design, settings, on_step, backend, debug, divisions,
                        follow_stable_branch)


def _inflate(design: Design, settings: SolverSettings, on_step: Callable[[dict], None] | None,
             backend: str, debug: bool, divisions: MeshDivisions | None,
             follow_stable_branch: bool) -> tuple[Curve, ActuatorModel, np.ndarray]:
    t_start = time.perf_counter()
    model = ActuatorModel(design, settings, divisions)
    curve, u = inflate_model(model, settings, on_step, backend, debug, follow_stable_branch,
                             t_start)
    return curve, model, u


@dataclass(frozen=True)
class Run:
    """What one solve holds fixed: the model (mm, Pa), its settings and stops, the linear
    solver's backend, whether it follows the stable branch (volume control only), and the
    curve's rows being written."""

    model: Any
    settings: SolverSettings
    backend: str
    debug: bool
    follow_stable_branch: bool
    stops: Stops
    columns: CurveColumns

    @property
    def volume_control(self) -> bool:
        return self.settings.control == "volume"


@dataclass
class PathState:
    """The continuation's state between steps: the last converged state (displacement u
    in mm, element pressures q and cavity pressure in Pa, its evaluation with the
    tangent), the converged states the predictor passes through, and the next load
    increment ``step`` (cavity volume in mm^3 under volume control, pressure in Pa under
    pressure control; the cut-backs' floor is ``MIN_CUTBACK`` of ``first_step``)."""

    u: np.ndarray
    q: list[np.ndarray]
    pressure_pa: float
    evaluation: Evaluation
    history: list[State]
    step: float
    first_step: float
    extrapolate: bool = True      # start the next step from the predictor
    failures_here: int = 0        # failed attempts from the current converged state
    fold_attempted: bool = False  # the switch at a failed step is tried once per curve (its
                                  # arc length costs minutes on the actuator)
    switch_index: int = -1        # the step at which the curve left the primary branch

    def state(self) -> tuple[np.ndarray, list[np.ndarray], float]:
        """The last converged (u, q, p)."""
        return self.u, self.q, self.pressure_pa

    def adopt(self, out: Converged) -> None:
        """``out`` as the last converged state."""
        self.u, self.pressure_pa, self.q, self.evaluation = (
            out.u, out.pressure_pa, out.q, out.evaluation)


def inflate_model(model, settings: SolverSettings,
                  on_step: Callable[[dict], None] | None = None, backend: str = "auto",
                  debug: bool = False, follow_stable_branch: bool = False,
                  t_start: float | None = None) -> tuple[Curve, np.ndarray]:
    """The load stepping of ``solve`` on a built model: an ``ActuatorModel``, or any
    ``SolidModel`` with a cavity that also provides ``end_face_kinematics(u) -> (angle,
    tip (2,))``, ``injected_volume_ul(half_volume)`` and ``tip_force_mn(evaluation)``
    (the reference problems of solver/verification, e.g. two balloons sharing one
    pressure). Returns the curve and the last converged displacement.

    The continuation: from the undeformed state, each step's load (cavity volume or
    pressure) is the last plus the step; Newton converges it from the Hermite predictor
    (from the converged state if that fails); a failed step is cut back, a converged one
    recorded, switched to the stable branch where it is unstable at constant volume
    (``follow_stable_branch``), and the next step sized (solver/step_size.py); the
    curve ends on the first stop reached, the last step landed on it (volume control)."""
    if t_start is None:
        t_start = time.perf_counter()
    columns = CurveColumns(model, on_step)
    path, failure = start_at_rest(model, settings, backend, columns)
    run = Run(model, settings, backend, debug,
              follow_stable_branch and settings.control == "volume",
              solve_stops(settings, model), columns)
    status, reason = "stopped", f"reached max_steps = {settings.max_steps}"
    if failure is not None:
        status, reason = "failed", failure
    for _ in range(0 if failure is not None else settings.max_steps):
        load = next_load(run, path)
        guess = predictor(path.history, load) if path.extrapolate else None
        try:
            out = converge_step(run, path, load, guess)
        except (StepFailed, FloatingPointError) as exc:
            failure = cut_back(run, path, load, guess is not None, exc)
            if failure is not None:
                status, reason = "failed", failure
                break
            continue
        before = (*path.state(), path.evaluation)
        solves = accept_step(run, path, load, out)
        if (run.follow_stable_branch and path.switch_index < 0
                and columns.last("volume_control_negative_eigenvalues") > 0):
            solves = switch_past_bifurcation(run, path, before, load, solves)
        path.step *= step_factor(solves,
                                 abs(columns.last("angle_deg") - columns.last("angle_deg", 2)),
                                 abs(path.pressure_pa - columns.last("pressure_pa", 2)),
                                 path.pressure_pa, run.volume_control)
        reached = stops_reached(run.stops.limits, last_stop_values(columns),
                                at_volume_cap=(run.volume_control
                                               and load >= run.stops.volume_cap_mm3))
        if reached:
            status, reason = "complete", end_on_stop(run, path, reached, before, load, solves)
            break
    return columns.curve(settings, status, reason, path.switch_index,
                         time.perf_counter() - t_start), path.u


def start_at_rest(model, settings: SolverSettings, backend: str, columns: CurveColumns
                  ) -> tuple[PathState, str | None]:
    """The undeformed state (u = 0, p = 0, element pressures consistent with u) as the
    curve's first row, and the path's tangent there (K^-1 g: the first step starts from
    the Euler predictor along it). Returns the path and None, or with the reason the
    curve fails there: a tangent at rest that cannot be solved (an inline material of
    mu = 5e-324 kPa: a stiffness of subnormal numbers, PARDISO's solution not finite)
    ends the curve, failed, as a step that does not converge does."""
    volume_control = settings.control == "volume"
    u = np.zeros(model.n_free)
    q = model.consistent_pressures(u)
    p = 0.0
    last = model.evaluate(u, p, pressures=q)
    columns.append(u, p, 0, 0.0, 0, last)
    step = first_step(volume_control, model.volume0_mm3, model.mu0_min_pa)
    path = PathState(u, q, p, last, [], step, step)
    try:
        b0 = counted_solve(model, counted_factorisation(model, last.K, backend), last.g)
    except (StepFailed, FloatingPointError) as exc:
        return path, f"the tangent at rest cannot be solved: {exc}"
    path.history = [State(model.volume0_mm3 if volume_control else 0.0, u, q, p,
                          path_rate(model, last, b0, float(last.g @ b0), volume_control))]
    return path, None


def next_load(run: Run, path: PathState) -> float:
    """The next step's load: the cavity volume (mm^3) under volume control, capped at the
    volume stop's; the pressure (Pa) under pressure control, capped at max_pressure_pa
    (the other stops: ``end_on_stop``)."""
    if run.volume_control:
        return min(path.evaluation.volume_mm3 + path.step, run.stops.volume_cap_mm3)
    return min(path.pressure_pa + path.step, run.settings.max_pressure_pa)


def converge_step(run: Run, path: PathState, load: float,
                  guess: tuple[np.ndarray, list[np.ndarray], float] | None) -> Converged:
    """Newton at ``load`` (solver/newton.py) from the predictor's ``guess``, or from the
    last converged state with its tangent; StepFailed (or FloatingPointError) if it does
    not converge."""
    u0, q0, p0, start = ((*path.state(), path.evaluation) if guess is None
                         else (*guess, None))
    target_volume, target_pressure = (load, None) if run.volume_control else (None, load)
    return mixed_newton_step(run.model, u0, q0, p0, run.settings, target_volume,
                             target_pressure, run.backend, start=start)


def cut_back(run: Run, path: PathState, load: float, extrapolated: bool,
             exc: Exception) -> str | None:
    """A step to ``load`` failed: retried from the converged state if it started from the
    predictor; else, when following the stable branch, past a fold after
    ``FAILURES_BEFORE_SWITCH`` failures (once per curve); else halved. Returns the
    reason the curve fails when the step falls below ``MIN_CUTBACK`` of the first."""
    model = run.model
    model.timings["cutbacks"] = model.timings.get("cutbacks", 0) + 1
    run.columns.report()
    if run.debug:
        print(f"cut-back at p = {path.pressure_pa:.1f}, step {path.step:.4g}: {exc}")
    path.failures_here += 1
    if extrapolated:
        path.extrapolate = False            # retry the same step from the converged state
        return None
    path.extrapolate = True
    if (run.follow_stable_branch and path.switch_index < 0
            and path.failures_here == FAILURES_BEFORE_SWITCH and not path.fold_attempted):
        path.fold_attempted = True
        if switch_past_fold(run, path, load):
            return None
    path.step *= 0.5
    if path.step < MIN_CUTBACK * path.first_step:
        return (f"step at p = {path.pressure_pa:.1f} Pa, angle = "
                f"{run.columns.last('angle_deg'):.1f} deg did not converge after "
                f"cut-backs: {exc}")
    return None


def switch_past_fold(run: Run, path: PathState, load: float) -> bool:
    """The switch at a step that keeps failing (a fold in volume, solver/
    branch_following.py) to the cavity volume ``load``: on success its state is recorded
    as the branch switch and the step halved."""
    switch = try_switch(run.model, run.settings, run.backend, path.state(), load, False,
                        len(run.columns) - 1, run.debug)
    if switch.converged is None:
        return False
    out = switch.converged
    path.adopt(out)
    path.history = [State(load, *path.state(), out.rate)]
    run.columns.append(path.u, path.pressure_pa, out.iterations, out.residual,
                       out.negative_pivots, path.evaluation, out.g_kinv_g)
    path.switch_index = len(run.columns) - 1
    path.failures_here = 0
    path.step = 0.5 * path.step
    return True


def accept_step(run: Run, path: PathState, load: float, out: Converged) -> int:
    """The step converged at ``load``: its state is the path's last and the predictor's
    newest, and the curve's new row. Returns its Newton solves."""
    path.adopt(out)
    path.extrapolate = True
    path.failures_here = 0
    path.history = (path.history + [State(load, *path.state(), out.rate)])[-PREDICTOR_POINTS:]
    run.columns.append(path.u, path.pressure_pa, out.iterations, out.residual,
                       out.negative_pivots, path.evaluation, out.g_kinv_g)
    return out.iterations


def switch_past_bifurcation(run: Run, path: PathState, before: tuple, load: float,
                            solves: int) -> int:
    """The step converged unstable at constant volume: where it crossed the bifurcation
    (the state ``before`` was stable), switch just past it (the pump's path leaves the
    primary branch there); else, or if that fails, at ``load``. A switch replaces the
    step's row. Returns the step's Newton solves, those to the located state included."""
    columns = run.columns
    near = (near_bifurcation(run.model, run.settings, run.backend, before[:3], path.state(),
                             before[3].volume_mm3, path.evaluation.volume_mm3, run.debug)
            if columns.last("volume_control_negative_eigenvalues", 2) == 0 else None)
    switch = None
    if near is not None:
        n_out, n_volume = near
        switch = try_switch(run.model, run.settings, run.backend,
                            (n_out.u, n_out.q, n_out.pressure_pa), n_volume, True,
                            len(columns) - 1, run.debug)
        solves += n_out.iterations
    if switch is None or switch.converged is None:
        n_volume = load
        switch = try_switch(run.model, run.settings, run.backend, path.state(), load, True,
                            len(columns) - 1, run.debug)
    if switch.converged is not None:
        out = switch.converged
        columns.drop_last()
        path.adopt(out)
        path.history = [State(n_volume, *path.state(), out.rate)]
        columns.append(path.u, path.pressure_pa, solves + out.iterations, out.residual,
                       out.negative_pivots, path.evaluation, out.g_kinv_g)
        path.switch_index = len(columns) - 1
    return solves


def last_stop_values(columns: CurveColumns, back: int = 1) -> dict[str, float]:
    """The stops' quantities at the curve's row ``back`` from the end."""
    return stop_values(columns.last("angle_deg", back), columns.last("pressure_pa", back),
                       columns.last("volume_ul", back))


def end_on_stop(run: Run, path: PathState, reached: list[str], before: tuple, load: float,
                solves: int) -> str:
    """The step to ``load`` reached the stops ``reached``: under volume control (and not
    a branch switch) it is replaced by the step landed on the stop met first
    (solver/stop_landing.py). Returns the curve's reason."""
    columns = run.columns
    stop = reached[0]
    if run.volume_control and path.switch_index != len(columns) - 1:
        landing = land_on_stop(run.model, run.settings, run.backend, run.stops, reached,
                               last_stop_values(columns, 2), last_stop_values(columns),
                               before, load, path.history)
        if landing is not None:
            stop, out, landing_solves = landing
            columns.drop_last()
            path.adopt(out)
            columns.append(path.u, path.pressure_pa, solves + landing_solves, out.residual,
                           out.negative_pivots, path.evaluation, out.g_kinv_g)
    ended = last_stop_values(columns)[stop]
    return stop_reason(stop, run.stops.limits[stop], ended, run.stops.user_stop[stop])
