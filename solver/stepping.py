"""Quasi-static inflation of the actuator: adaptive load stepping with Newton.

Two controls:

* pressure: each step prescribes p; Newton solves K du = -R.
* volume (a fluid cavity, as in Abaqus or FEBio): each step prescribes the
  injected volume; the pressure is an extra unknown. Newton on the bordered system

      [ K    -g ] [du]   [ -R       ]
      [ -g^T  0 ] [dp] = [ V - V_t  ]

  solved with one factorisation of K and two back-substitutions. It passes
  pressure plateaus and maxima, as the syringe-pump experiment does.

The Newton iterate is the mixed u-q pair (element pressures q as unknowns, condensed
per element; solver/assembly.py): with the penalty form, the spurious second-order
dilatation of a large rotating predictor step, times the bulk modulus, made the
tangent indefinite and forced ~2.5 degree steps; the mixed iterate takes the full
target step (benchmarks/RESULTS.md).

Steps restart from the last converged state (no extrapolating predictor: it
caused most Newton failures in earlier prototypes); a failed step is cut back
by half; the step grows when Newton converges quickly and shrinks when the
angle increment is large, aiming at ~8 degrees and at most ~150 Pa per step (so
that the curve is resolved where the angle is small and the pressure rises fast).
A step that cannot converge after the cut-backs ends the curve with status
"failed" and the reason.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from threadpoolctl import ThreadpoolController

from solver.curve import Curve
from solver.design import Design
from solver.linear import factorize
from solver.mesh import DEFAULT_DIVISIONS, MeshDivisions
from solver.model import ActuatorModel, Evaluation
from solver.settings import SolverSettings

TARGET_ANGLE_STEP_DEG = 8.0
MAX_PRESSURE_STEP_PA = 150.0   # output resolution where the curve is steep in pressure
MIN_CUTBACK = 1.0 / 1024.0
DIVERGENCE_FLOOR = 1e-3   # below this relative residual a rise is round-off, not divergence


class StepFailed(Exception):
    """A load step did not converge; the caller cuts the step back."""



def newton_step(model: ActuatorModel, u: np.ndarray, p: float, settings: SolverSettings,
                target_volume: float | None, target_pressure: float | None, backend: str):
    """Converge one load step from (u, p); returns (u, p, iterations, residual, negative
    pivots). The element pressures start consistent with u (see ``mixed_newton_step``)."""
    out = mixed_newton_step(model, u, model.consistent_pressures(u), p, settings,
                            target_volume, target_pressure, backend)
    return out.u, out.pressure_pa, out.iterations, out.residual, out.negative_pivots


@dataclass
class Converged:
    """A converged load step: the state, how it was reached, and its evaluation
    (residual and tangent at the state, reused by the next volume step)."""

    u: np.ndarray
    q: list[np.ndarray]
    pressure_pa: float
    iterations: int
    residual: float
    negative_pivots: int
    evaluation: Evaluation


def mixed_newton_step(model: ActuatorModel, u: np.ndarray, q: list[np.ndarray], p: float,
                      settings: SolverSettings, target_volume: float | None,
                      target_pressure: float | None, backend: str,
                      start: Evaluation | None = None) -> Converged:
    """Converge one load step of the mixed u-q form (q: element pressures per block).

    ``start``: the evaluation at (u, q, p) when known (a volume step starting from the
    last converged state). Converged when the condensed residual, the cavity volume
    and the dilatation constraint are all below ``settings.newton_tol`` (relative to
    the pressure load, the chamber volume, and absolute strain).
    """
    tol = settings.newton_tol
    force_floor = model.mu0_min_pa * 1e-6
    volume_scale = max(model.volume0_mm3, 1e-9)
    neg = -1
    first_res = None
    predictor_res = np.inf
    previous_res = np.inf
    du, dp = None, 0.0
    dq: list[np.ndarray] = []
    for it in range(1, settings.max_newton_iter + 1):
        if target_pressure is not None:
            p = target_pressure
        ev = None
        if du is None:
            ev = start if start is not None and target_pressure is None else (
                model.evaluate(u, p, pressures=q))
        else:
            # Damped update: halve it while it would invert an element.
            scale = 1.0
            for _ in range(6):
                try:
                    q_try = [qb + scale * d for qb, d in zip(q, dq)]
                    ev = model.evaluate(u + scale * du, p + scale * dp, pressures=q_try)
                    break
                except FloatingPointError:
                    scale *= 0.5
            if ev is None:
                raise StepFailed(f"every damped Newton update inverts an element (iteration {it},"
                                 f" |du|max = {np.abs(du).max():.3g} mm, dp = {dp:.3g} Pa)")
            u, p, q = u + scale * du, p + scale * dp, q_try
        res = float(np.linalg.norm(ev.R)) / max(ev.load_norm, force_floor)
        vres = 0.0 if target_volume is None else abs(ev.volume_mm3 - target_volume) / volume_scale
        if not np.isfinite(res):
            raise StepFailed("non-finite residual")
        if first_res is None:
            first_res = max(res, vres)
        elif max(res, vres) > 1e6 * max(first_res, 1.0):
            raise StepFailed("Newton diverged")
        if it == 2:
            predictor_res = res
        elif it > 2 and res > predictor_res and res > DIVERGENCE_FLOOR:
            # Worse than right after the predictor: this step is leaving the basin of
            # convergence; cutting back now is cheaper than iterating on.
            raise StepFailed(f"Newton diverging at iteration {it} (residual {res:.2e})")
        # Converged below the tolerance, or stalled at the rounding floor (which grows
        # with the bulk modulus) within 100 x the tolerance.
        floor = it > 2 and res < 100 * tol and res > 0.3 * previous_res
        if it > 1 and vres < tol and ev.constraint_error < tol and (res < tol or floor):
            return Converged(u, q, p, it - 1, res, neg, ev)
        previous_res = res
        t0 = time.perf_counter()
        try:
            fac = factorize(ev.K, backend)
            if target_volume is None:
                a = fac.solve(-ev.R)
            else:                               # both right-hand sides in one pass
                a, b = fac.solve(np.column_stack((-ev.R, ev.g))).T
        except (np.linalg.LinAlgError, RuntimeError) as exc:
            raise StepFailed(f"linear solve failed: {exc}") from None
        finally:
            model.timings["linear_solve_s"] += time.perf_counter() - t0
        neg = fac.negative_pivots
        if target_volume is None:
            du, dp = a, 0.0
        else:
            gb = float(ev.g @ b)
            if gb == 0.0 or not np.isfinite(gb):
                raise StepFailed("bordered system singular (g^T K^-1 g = 0)")
            dp = -(ev.volume_mm3 - target_volume + float(ev.g @ a)) / gb
            du = a + b * dp
        dq = model.pressure_update(ev, du)
    raise StepFailed(f"no convergence in {settings.max_newton_iter} Newton iterations "
                      f"(residual {res:.2e})")


def solve(design: Design, settings: SolverSettings | None = None,
          on_step: Callable[[dict], None] | None = None, backend: str = "auto",
          divisions: MeshDivisions = DEFAULT_DIVISIONS) -> Curve:
    """Inflate ``design`` until a stop criterion; return the curve.

    Raises InputError for invalid input only; a solve that fails returns a Curve
    with status "failed" and the reason.
    """
    return inflate(design, settings, on_step, backend, divisions=divisions)[0]


def inflate(design: Design, settings: SolverSettings | None = None,
            on_step: Callable[[dict], None] | None = None, backend: str = "auto",
            debug: bool = False, divisions: MeshDivisions = DEFAULT_DIVISIONS
            ) -> tuple[Curve, ActuatorModel, np.ndarray]:
    """Like ``solve``, also returning the discrete model and the last converged
    displacement (free dofs), for field output (VTK). ``divisions``: the level-0 mesh
    resolution (convergence studies only; records assume the default).

    numpy's OpenBLAS is held to one thread meanwhile: its idle threads spin and take
    the cores from MKL PARDISO's, which does the parallel work (benchmarks/RESULTS.md).
    """
    settings = (settings or SolverSettings()).validated()
    design = design.validated()
    with ThreadpoolController().select(internal_api="openblas").limit(limits=1):
        return _inflate(design, settings, on_step, backend, debug, divisions)


def _inflate(design: Design, settings: SolverSettings, on_step: Callable[[dict], None] | None,
             backend: str, debug: bool, divisions: MeshDivisions
             ) -> tuple[Curve, ActuatorModel, np.ndarray]:
    t_start = time.perf_counter()
    model = ActuatorModel(design, settings, divisions)
    volume_control = settings.control == "volume"

    u = np.zeros(model.n_free)
    q = model.consistent_pressures(u)
    p = 0.0
    rows: dict[str, list] = {k: [] for k in ("p", "v", "a", "tip", "lam", "it", "res", "neg", "f")}

    def record(u_: np.ndarray, p_: float, it: int, res: float, neg: int, ev: Evaluation
               ) -> float:
        angle, tip = model.end_face_kinematics(u_)
        rows["p"].append(p_)
        rows["v"].append(model.injected_volume_ul(ev.volume_mm3))
        rows["a"].append(angle)
        rows["tip"].append(tip)
        rows["lam"].append(ev.max_membrane_stretch)
        rows["it"].append(it)
        rows["res"].append(res)
        rows["neg"].append(neg)
        rows["f"].append(model.tip_force_mn(ev))
        if on_step is not None and len(rows["p"]) > 1:
            on_step({"step": len(rows["p"]) - 1, "pressure_pa": p_,
                     "volume_ul": rows["v"][-1], "angle_deg": angle, "newton_iterations": it})
        return angle

    last = model.evaluate(u, p, pressures=q)
    record(u, p, 0, 0.0, 0, last)
    # Initial increments: a small fraction of the chamber volume, or of the membrane modulus.
    step = 0.05 * model.volume0_mm3 if volume_control else 0.05 * model.mu0_min_pa
    initial_step = step
    status, reason = "stopped", f"reached max_steps = {settings.max_steps}"
    for _ in range(settings.max_steps):
        try:
            if volume_control:
                vt = model.volume0_mm3 + 0.5 * rows["v"][-1] + step
                step_out = mixed_newton_step(model, u, q, p, settings, vt, None, backend,
                                             start=last)
            else:
                step_out = mixed_newton_step(model, u, q, p, settings, None, p + step, backend)
        except (StepFailed, FloatingPointError) as exc:
            model.timings["cutbacks"] = model.timings.get("cutbacks", 0) + 1
            if debug:
                print(f"cut-back at p = {p:.1f}, step {step:.4g}: {exc}")
            step *= 0.5
            if step < MIN_CUTBACK * initial_step:
                status, reason = "failed", (f"step at p = {p:.1f} Pa, angle = "
                                            f"{rows['a'][-1]:.1f} deg did not converge after "
                                            f"cut-backs: {exc}")
                break
            continue
        u, p, q, last = step_out.u, step_out.pressure_pa, step_out.q, step_out.evaluation
        its = step_out.iterations
        angle = record(u, p, its, step_out.residual, step_out.negative_pivots, last)
        d_angle = abs(angle - rows["a"][-2])
        factor = 1.6 if its <= 6 else (1.0 if its <= 9 else 0.6)
        if d_angle > 1e-9:
            factor = min(factor, max(0.5, TARGET_ANGLE_STEP_DEG / d_angle))
        d_pressure = abs(p - rows["p"][-2])
        if volume_control and d_pressure > 1e-9:
            factor = min(factor, max(0.5, MAX_PRESSURE_STEP_PA / d_pressure))
        step *= factor
        if abs(angle) >= settings.max_angle_deg:
            status, reason = "complete", f"reached max_angle_deg = {settings.max_angle_deg}"
            break
        if p >= settings.max_pressure_pa:
            status, reason = "complete", f"reached max_pressure_pa = {settings.max_pressure_pa}"
            break
        if rows["v"][-1] >= settings.max_volume_ul:
            status, reason = "complete", f"reached max_volume_ul = {settings.max_volume_ul}"
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
        wall_time_s=time.perf_counter() - t_start, timings_s=dict(model.timings))
    return curve, model, u
