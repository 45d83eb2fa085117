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
and the pressure rises fast).
A step that cannot converge after the cut-backs ends the curve with status
"failed" and the reason.

The curve ends on its stop, not one step past it. Under pressure control the last step's
pressure is capped at max_pressure_pa, under volume control its volume at max_volume_ul;
and a volume step that converged past max_angle_deg or max_pressure_pa is replaced by one
from the previous converged state to the volume at which the stop is met (solver/
landing.py: interpolated, then up to two secant corrections, and for a stop other than
the defaults' up to ten Illinois corrections; the landed state at or past the stop by at
most 0.1 % of it and 0.01 deg). Only the curve's last point moves; where no landing
converges nearer the stop, or the step switched branch, the step past the stop ends the
curve, as before the landing (a user's stop's reason then says where it ended).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np
from threadpoolctl import ThreadpoolController

from solver.branching import lowest_volume_neutral_mode, pass_fold, switch_branch
from solver.curve import Curve
from solver.design import Design
from solver.discrete import ActuatorModel, Evaluation
from solver.hermite_predictor import PREDICTOR_POINTS, State, path_rate, predictor
from solver.landing import (
    STOPS,
    USER_STOP_CORRECTIONS,
    Point,
    interpolated_load,
    land,
    landing_tolerance,
    stop_reason,
    stop_values,
    stops_reached,
    volume_load_at,
)
from solver.mesh import MeshDivisions
from solver.newton import (
    Converged,
    StepFailed,
    counted_factorisation,
    counted_solve,
    mixed_newton_step,
)
from solver.settings import SolverSettings
from solver.stability import volume_control_index

TARGET_ANGLE_STEP_DEG = 8.0
MAX_PRESSURE_STEP_PA = 150.0   # output resolution where the curve is steep in pressure,
MAX_RELATIVE_PRESSURE_STEP = 0.08   # or 8 % of the pressure when that is more (a blocked
                                    # tip climbing to kPa: ~45 steps to 20 kPa, not 130)
GROW_SOLVES = 4     # a step converged in at most this many Newton solves grows the next 1.6x,
HOLD_SOLVES = 7     # in at most this many keeps it, otherwise shrinks it to 0.6x (the
                    # Hermite predictor takes ~2 solves where the parabola took 3-4: these
                    # were 6 and 9 with the parabola)
MIN_CUTBACK = 1.0 / 1024.0
DEFAULT_SETTINGS = SolverSettings()   # its stops are the database's (solver/landing.py)
FAILURES_BEFORE_SWITCH = 6   # follow_stable_branch: failed attempts from one converged state
                             # (extrapolated and plain, each size; the step cut to 1/4) before
                             # the branch switch is tried at the last failed volume
SWITCH_NEWTON_ITER = 12      # Newton iterations allowed when the mode's amplitude is released
BIFURCATION_OVERSHOOT = 0.25  # the switch is made this share of the way from the located
                              # bifurcation to the unstable state that revealed it


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


def inflate_model(model, settings: SolverSettings,
                  on_step: Callable[[dict], None] | None = None, backend: str = "auto",
                  debug: bool = False, follow_stable_branch: bool = False,
                  t_start: float | None = None) -> tuple[Curve, np.ndarray]:
    """The load stepping of ``solve`` on a built model: an ``ActuatorModel``, or any
    ``SolidModel`` with a cavity that also provides ``end_face_kinematics(u) -> (angle,
    tip (2,))``, ``injected_volume_ul(half_volume)`` and ``tip_force_mn(evaluation)``
    (the reference problems of solver/verification, e.g. two balloons sharing one
    pressure). Returns the curve and the last converged displacement."""
    if t_start is None:
        t_start = time.perf_counter()
    volume_control = settings.control == "volume"

    u = np.zeros(model.n_free)
    q = model.consistent_pressures(u)
    p = 0.0
    rows: dict[str, list] = {k: [] for k in ("p", "v", "a", "tip", "lam", "it", "res", "neg", "f",
                                             "negv")}

    def record(u_: np.ndarray, p_: float, it: int, res: float, neg: int, ev: Evaluation,
               g_kinv_g: float = 1.0) -> float:
        angle, tip = model.end_face_kinematics(u_)
        rows["negv"].append(volume_control_index(neg, g_kinv_g) if neg >= 0 else neg)
        rows["p"].append(p_)
        rows["v"].append(model.injected_volume_ul(ev.volume_mm3))
        rows["a"].append(angle)
        rows["tip"].append(tip)
        rows["lam"].append(ev.max_membrane_stretch)
        rows["it"].append(it)
        rows["res"].append(res)
        rows["neg"].append(neg)
        rows["f"].append(model.tip_force_mn(ev))
        report_step()
        return angle

    def report_step() -> None:
        """The last converged step to ``on_step``, with the cut-backs so far: after every
        converged step and after every cut-back (a job's page then says why the curve
        stands still: 70 s at one pressure had looked like a hang); a step landed on a
        stop is reported again under the same number as the step past it it replaces."""
        if on_step is not None and len(rows["p"]) > 1:
            on_step({"step": len(rows["p"]) - 1, "pressure_pa": rows["p"][-1],
                     "volume_ul": rows["v"][-1], "angle_deg": rows["a"][-1],
                     "newton_iterations": rows["it"][-1],
                     "cutbacks": int(model.timings.get("cutbacks", 0))})

    switch_settings = replace(settings, max_newton_iter=SWITCH_NEWTON_ITER)

    def try_switch(u_, q_, p_, volume, at_target):
        """One branch-switch attempt from the converged state (u_, q_, p_) to a stable
        state at the cavity volume ``volume`` (solver/branching.py): along the unstable
        mode if the state is at that volume; otherwise (a failed step) over a fold in
        volume by arc length first, then along the lowest volume-neutral mode."""
        def converge(us, qs, ps):
            return mixed_newton_step(model, us, qs, ps, switch_settings, volume, None,
                                     backend, patient=True)
        attempts = ((switch_branch,) if at_target else (pass_fold, switch_branch))
        for attempt in attempts:
            if attempt is switch_branch:
                switch = switch_branch(model, u_, q_, p_, volume, converge, backend,
                                       settings.newton_tol, at_target)
            else:
                switch = pass_fold(model, u_, q_, p_, volume, converge, backend,
                                   settings.newton_tol)
            model.timings["branch_switch_attempts"] = (
                model.timings.get("branch_switch_attempts", 0) + 1)
            if debug:
                print(f"branch switch after step {len(rows['p']) - 1}: {switch.reason}")
            if switch.converged is not None:
                break
        return switch

    def near_bifurcation(a, b, volume_a, volume_b):
        """A converged primary state just past the bifurcation crossed between the
        converged states a (stable at constant volume) and b (unstable), each (u, q, p):
        the lowest volume-neutral eigenvalue interpolated linearly in volume to zero,
        then ``BIFURCATION_OVERSHOOT`` of the way on towards b. Returns (Converged,
        volume), or None if that state does not converge or is not unstable."""
        mu_a = lowest_volume_neutral_mode(model, *a, backend)[0]
        mu_b = lowest_volume_neutral_mode(model, *b, backend)[0]
        if not mu_a > 0.0 > mu_b:
            return None
        critical = volume_a + (volume_b - volume_a) * mu_a / (mu_a - mu_b)
        volume = critical + BIFURCATION_OVERSHOOT * (volume_b - critical)
        try:
            out = mixed_newton_step(model, *a, settings, volume, None, backend)
        except (StepFailed, FloatingPointError):
            return None
        if lowest_volume_neutral_mode(model, out.u, out.q, out.pressure_pa, backend)[0] >= 0:
            return None
        if debug:
            print(f"bifurcation located at {critical:.6g} mm^3 (eigenvalues {mu_a:.3g}, "
                  f"{mu_b:.3g} uN/mm at {volume_a:.6g}, {volume_b:.6g}); switching at "
                  f"{volume:.6g}")
        return out, volume

    def land_on_stop(reached: list[str], before: tuple, after_load: float,
                     history_: list[State]) -> tuple[str, Converged, int] | None:
        """The last converged step (rows[-1], at the volume ``after_load``) reached the
        stops ``reached``: the converged state on the stop met first from ``before`` (the
        previous converged state (u, q, p, evaluation), rows[-2]), by solver/landing.py,
        as (stop, state, its Newton solves); None where the step needs no landing (it
        is on the volume stop, or ``before`` was past a stop too) or none converged
        nearer the stop than the step itself (the curve then ends on it, as before).
        Each landing step starts from the Hermite predictor through the last converged
        states (the step past the stop among them: an interpolation), else from
        ``before``."""
        was = stop_values(rows["a"][-2], rows["p"][-2], rows["v"][-2])
        now = stop_values(rows["a"][-1], rows["p"][-1], rows["v"][-1])
        if any(was[name] >= limits[name] for name in reached):
            return None
        before_load = before[3].volume_mm3
        loads = {name: volume_stop_mm3 if name == "max_volume_ul" else interpolated_load(
            limits[name], Point(before_load, was[name]), Point(after_load, now[name]))
            for name in reached}
        stop = min(reached, key=lambda name: loads[name])     # met first along the step
        if stop == "max_volume_ul":
            return None
        tried = list(history_)
        solves = 0

        def converge(load_: float) -> Point | None:
            nonlocal solves
            model.timings["landing_steps"] = model.timings.get("landing_steps", 0) + 1
            guess = predictor(tried, load_)
            for u0, q0, p0, start in ([] if guess is None else [(*guess, None)]) + [before]:
                try:
                    out = mixed_newton_step(model, u0, q0, p0, settings, load_, None,
                                            backend, start=start)
                except (StepFailed, FloatingPointError):
                    continue
                solves += out.iterations
                tried.append(State(load_, out.u, out.q, out.pressure_pa, out.rate))
                del tried[:-PREDICTOR_POINTS]
                values = stop_values(model.end_face_kinematics(out.u)[0], out.pressure_pa,
                                     model.injected_volume_ul(out.evaluation.volume_mm3))
                return Point(load_, values[stop], out)
            return None

        limit = limits[stop]
        best = land(limit, landing_tolerance(stop, limit), Point(before_load, was[stop]),
                    Point(after_load, now[stop]), converge,
                    further=USER_STOP_CORRECTIONS if user_stop[stop] else 0)
        if best is None or abs(best.value - limit) >= abs(now[stop] - limit):
            return None
        return stop, best.state, solves

    last = model.evaluate(u, p, pressures=q)
    record(u, p, 0, 0.0, 0, last)
    # Initial increments: a small fraction of the chamber volume, or of the membrane modulus.
    step = 0.05 * model.volume0_mm3 if volume_control else 0.05 * model.mu0_min_pa
    initial_step = step
    status, reason = "stopped", f"reached max_steps = {settings.max_steps}"
    # The path's tangent at the undeformed state: the first step starts from the Euler
    # predictor along it.
    # A tangent at rest that cannot be solved (an inline material of mu = 5e-324 kPa: a
    # stiffness of subnormal numbers, PARDISO's solution not finite) ends the curve there,
    # failed, as a step that does not converge does: it escaped solve() as StepFailed.
    try:
        b0 = counted_solve(model, counted_factorisation(model, last.K, backend), last.g)
        history = [State(model.volume0_mm3 if volume_control else 0.0, u, q, p,
                         path_rate(model, last, b0, float(last.g @ b0), volume_control))]
        steps = settings.max_steps
    except (StepFailed, FloatingPointError) as exc:
        status, reason = "failed", f"the tangent at rest cannot be solved: {exc}"
        steps = 0
    extrapolate = True
    switch_index = -1
    limits = {name: getattr(settings, name) for name in STOPS}
    # a stop the user chose (not the default's, where the database's curves end): landed
    # with the Illinois corrections too, and its reason says where a curve ended off it
    user_stop = {name: limits[name] != getattr(DEFAULT_SETTINGS, name) for name in STOPS}
    # The cavity volume at max_volume_ul, and past it by the Newton tolerance on the
    # volume (so that the state converged there is at or past the stop): the last volume
    # step is capped at it.
    volume_stop_mm3 = (volume_load_at(settings.max_volume_ul, model.injected_volume_ul,
                                      model.volume0_mm3)
                       + settings.newton_tol * model.volume0_mm3 if volume_control else np.inf)
    fold_attempted = False       # the switch at a failed step is tried once per curve (its
                                 # arc length costs minutes on the actuator)
    failures_here = 0            # failed attempts from the current converged state
    for _ in range(steps):
        # The last step lands on max_volume_ul under volume control and on max_pressure_pa
        # under pressure control, not beyond it (the other stops: ``land_on_stop``).
        load = min(last.volume_mm3 + step, volume_stop_mm3) if volume_control else (
            min(p + step, settings.max_pressure_pa))
        guess = predictor(history, load) if extrapolate else None
        try:
            u0, q0, p0, start = (u, q, p, last) if guess is None else (*guess, None)
            if volume_control:
                step_out = mixed_newton_step(model, u0, q0, p0, settings, load, None, backend,
                                             start=start)
            else:
                step_out = mixed_newton_step(model, u0, q0, p0, settings, None, load, backend,
                                             start=start)
        except (StepFailed, FloatingPointError) as exc:
            model.timings["cutbacks"] = model.timings.get("cutbacks", 0) + 1
            report_step()
            if debug:
                print(f"cut-back at p = {p:.1f}, step {step:.4g}: {exc}")
            failures_here += 1
            if guess is not None:
                extrapolate = False            # retry the same step from the converged state
                continue
            extrapolate = True
            if (follow_stable_branch and volume_control and switch_index < 0
                    and failures_here == FAILURES_BEFORE_SWITCH and not fold_attempted):
                fold_attempted = True
                switch = try_switch(u, q, p, load, at_target=False)
                if switch.converged is not None:
                    out = switch.converged
                    u, p, q, last = out.u, out.pressure_pa, out.q, out.evaluation
                    history = [State(load, u, q, p, out.rate)]
                    angle = record(u, p, out.iterations, out.residual, out.negative_pivots,
                                   last, out.g_kinv_g)
                    switch_index = len(rows["p"]) - 1
                    failures_here = 0
                    step = 0.5 * step
                    continue
            step *= 0.5
            if step < MIN_CUTBACK * initial_step:
                status, reason = "failed", (f"step at p = {p:.1f} Pa, angle = "
                                            f"{rows['a'][-1]:.1f} deg did not converge after "
                                            f"cut-backs: {exc}")
                break
            continue
        before = (u, q, p, last)
        u, p, q, last = step_out.u, step_out.pressure_pa, step_out.q, step_out.evaluation
        extrapolate = True
        failures_here = 0
        history = (history + [State(load, u, q, p, step_out.rate)])[-PREDICTOR_POINTS:]
        its = step_out.iterations
        angle = record(u, p, its, step_out.residual, step_out.negative_pivots, last,
                       step_out.g_kinv_g)
        if (follow_stable_branch and volume_control and switch_index < 0
                and rows["negv"][-1] > 0):
            # Where the step crossed the bifurcation, switch just past it (the pump's
            # path leaves the primary branch there); else, or if that fails, here.
            near = (near_bifurcation(before[:3], (u, q, p), before[3].volume_mm3,
                                     last.volume_mm3)
                    if rows["negv"][-2] == 0 else None)
            switch = None
            if near is not None:
                n_out, n_volume = near
                switch = try_switch(n_out.u, n_out.q, n_out.pressure_pa, n_volume, True)
                its += n_out.iterations
            if switch is None or switch.converged is None:
                n_volume = load
                switch = try_switch(u, q, p, load, at_target=True)
            if switch.converged is not None:
                out = switch.converged
                for column in rows.values():
                    column.pop()
                u, p, q, last = out.u, out.pressure_pa, out.q, out.evaluation
                history = [State(n_volume, u, q, p, out.rate)]
                angle = record(u, p, its + out.iterations, out.residual, out.negative_pivots,
                               last, out.g_kinv_g)
                switch_index = len(rows["p"]) - 1
        d_angle = abs(angle - rows["a"][-2])
        factor = 1.6 if its <= GROW_SOLVES else (1.0 if its <= HOLD_SOLVES else 0.6)
        if d_angle > 1e-9:
            factor = min(factor, max(0.5, TARGET_ANGLE_STEP_DEG / d_angle))
        d_pressure = abs(p - rows["p"][-2])
        if volume_control and d_pressure > 1e-9:
            allowed = max(MAX_PRESSURE_STEP_PA, MAX_RELATIVE_PRESSURE_STEP * abs(p))
            factor = min(factor, max(0.5, allowed / d_pressure))
        step *= factor
        reached = stops_reached(limits, stop_values(angle, p, rows["v"][-1]),
                                at_volume_cap=volume_control and load >= volume_stop_mm3)
        if reached:
            stop = reached[0]
            if volume_control and switch_index != len(rows["p"]) - 1:
                landing = land_on_stop(reached, before, load, history)
                if landing is not None:
                    stop, out, landing_solves = landing
                    for column in rows.values():
                        column.pop()
                    u, p, q, last = out.u, out.pressure_pa, out.q, out.evaluation
                    record(u, p, its + landing_solves, out.residual, out.negative_pivots,
                           last, out.g_kinv_g)
            ended = stop_values(rows["a"][-1], rows["p"][-1], rows["v"][-1])[stop]
            status, reason = "complete", stop_reason(stop, limits[stop], ended,
                                                     user_stop[stop])
            break

    pressure = np.array(rows["p"])
    pmax = -1
    if volume_control and len(pressure) > 2:
        drops = np.nonzero(np.diff(pressure) < 0)[0]
        if len(drops):
            pmax = int(drops[0])
    volume = np.array(rows["v"])
    n = len(pressure)
    curve = Curve(
        pressure_pa=pressure, volume_ul=volume, time_s=volume / settings.flow_ul_s,
        angle_deg=np.array(rows["a"]), tip_displacement_mm=np.array(rows["tip"]).reshape(n, 2),
        max_membrane_stretch=np.array(rows["lam"]), force_mn=np.array(rows["f"]),
        newton_iterations=np.array(rows["it"], dtype=np.int64),
        residual_norm=np.array(rows["res"]),
        negative_eigenvalues=np.array(rows["neg"], dtype=np.int64),
        status=status, reason=reason, pressure_maximum_index=pmax, n_dofs=model.n_free,
        wall_time_s=time.perf_counter() - t_start, timings_s=dict(model.timings),
        volume_control_negative_eigenvalues=np.array(rows["negv"], dtype=np.int64),
        branch_switch_index=switch_index)
    return curve, u
