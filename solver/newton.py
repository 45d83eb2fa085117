"""One load step converged by Newton's method on the mixed u-q iterate (element pressures
q as unknowns, condensed per element; solver/assembly.py), under pressure or volume
control.

Under volume control (a fluid cavity, as in Abaqus or FEBio) the pressure is an extra
unknown: Newton on the bordered system

    [ K    -g ] [du]   [ -R       ]
    [ -g^T  0 ] [dp] = [ V - V_t  ]

solved with one factorisation of K and two back-substitutions (a = K^-1 (-R), b = K^-1 g;
dp = -(V - V_t + g . a) / g . b, du = a + b dp). Near the solution the iterate is
evaluated without its tangent first and corrected with the last factorisation (chord
updates) while that converges fast (CHORD_SWITCH and CHORD_RATE tuned by counts,
benchmarks/RESULTS.md); neither changes the converged state beyond the Newton tolerance.
Displacements in mm, pressures in Pa, volumes in mm^3 (the half model's cavity).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from solver.discrete import ActuatorModel, Evaluation
from solver.hermite_predictor import Rate, path_rate
from solver.linear import factorize
from solver.settings import SolverSettings

DIVERGENCE_FLOOR = 1e-3   # below this relative residual a rise is round-off, not divergence
CHORD_SWITCH = 0.1        # error below which the next iterate is evaluated without tangent
CHORD_RATE = 0.1          # a chord update must shrink the error by this factor


class StepFailed(Exception):
    """A load step did not converge; the caller cuts the step back."""


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
    g_kinv_g: float = float("nan")   # g^T K^-1 g at the last factorisation (= dV/dp)
    rate: Rate | None = None         # the path's tangent, from the last linear solve


def counted_factorisation(model: ActuatorModel, K, backend: str):
    """``factorize`` timed and counted in ``model.timings``; StepFailed if singular."""
    t0 = time.perf_counter()
    try:
        fac = factorize(K, backend)
    except (np.linalg.LinAlgError, RuntimeError) as exc:
        raise StepFailed(f"linear solve failed: {exc}") from None
    finally:
        model.timings["linear_solve_s"] += time.perf_counter() - t0
    model.timings["factorisations"] = model.timings.get("factorisations", 0) + 1
    return fac


def counted_solve(model: ActuatorModel, fac, rhs: np.ndarray) -> np.ndarray:
    """``fac.solve(rhs)`` timed in ``model.timings``; StepFailed if it fails."""
    t0 = time.perf_counter()
    try:
        return fac.solve(rhs)
    except (np.linalg.LinAlgError, RuntimeError) as exc:
        raise StepFailed(f"linear solve failed: {exc}") from None
    finally:
        model.timings["linear_solve_s"] += time.perf_counter() - t0


def mixed_newton_step(model: ActuatorModel, u: np.ndarray, q: list[np.ndarray], p: float,
                      settings: SolverSettings, target_volume: float | None,
                      target_pressure: float | None, backend: str,
                      start: Evaluation | None = None, patient: bool = False) -> Converged:
    """Converge one load step of the mixed u-q form (q: element pressures per block).

    ``start``: the evaluation at (u, q, p) when known (a volume step starting from the
    last converged state, with its tangent). Converged when the condensed residual, the
    cavity volume and the dilatation constraint are all below ``settings.newton_tol``
    (relative to the pressure load, the chamber volume, and absolute strain).

    Full Newton while the iterate is far; once the error measure is below
    ``CHORD_SWITCH`` the next iterate is evaluated without its tangent (a third of the
    cost): converged, or a chord update with the last factorisation while that
    contracts the error by ``CHORD_RATE`` per update (near the solution the chord
    update is nearly as good as Newton's: the tangent changes by O(|du|)); otherwise
    the tangent is assembled again. ``iterations`` counts linear solves.

    ``patient``: no cut-off when the residual rises above the first iterate's (a start
    perturbed off an equilibrium branch may climb before it converges).
    """
    tol = settings.newton_tol
    force_floor = model.mu0_min_pa * 1e-6
    volume_scale = max(model.volume0_mm3, 1e-9)
    neg = -1
    first_res = None
    predictor_res = np.inf
    previous_res = np.inf
    previous_err = np.inf
    du, dp = None, 0.0
    dq: list[np.ndarray] = []
    fac = None
    want_tangent = True
    chord = False                   # the last update reused an older factorisation
    solves = 0
    res = np.inf
    gb = float("nan")
    b = ev_solved = None
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
                    ev = model.evaluate(u + scale * du, p + scale * dp, tangent=want_tangent,
                                        pressures=q_try)
                    break
                except FloatingPointError:
                    scale *= 0.5
            if ev is None:
                raise StepFailed(f"every damped Newton update inverts an element (iteration {it},"
                                 f" |du|max = {np.abs(du).max():.3g} mm, dp = {dp:.3g} Pa)")
            u, p, q = u + scale * du, p + scale * dp, q_try
        res = float(np.linalg.norm(ev.R)) / max(ev.load_norm, force_floor)
        vres = 0.0 if target_volume is None else abs(ev.volume_mm3 - target_volume) / volume_scale
        err = max(res, vres, ev.constraint_error)
        if not np.isfinite(res):
            raise StepFailed("non-finite residual")
        if first_res is None:
            first_res = max(res, vres)
        elif max(res, vres) > 1e6 * max(first_res, 1.0):
            raise StepFailed("Newton diverged")
        if it == 2:
            predictor_res = res
        elif (it > 2 and res > predictor_res and res > DIVERGENCE_FLOOR and not patient
              and not chord):
            # Worse than right after the predictor: this step is leaving the basin of
            # convergence; cutting back now is cheaper than iterating on. (A chord update
            # that made it worse is followed by a fresh tangent instead, below.)
            raise StepFailed(f"Newton diverging at iteration {it} (residual {res:.2e})")
        # Converged below the tolerance, or stalled at the rounding floor (which grows
        # with the bulk modulus) within 100 x the tolerance.
        # (Not after a chord update: its slower, linear convergence is no stall.)
        floor = it > 2 and res < 100 * tol and res > 0.3 * previous_res and not chord
        if it > 1 and vres < tol and ev.constraint_error < tol and (res < tol or floor):
            return Converged(u, q, p, solves, res, neg, ev, gb,
                             path_rate(model, ev_solved, b, gb, target_volume is not None))
        if ev.K is None and (fac is None or err > CHORD_RATE * previous_err):
            # The chord update would contract too slowly: assemble the tangent here.
            ev = model.evaluate(u, p, pressures=q)
            fac = None
        previous_res = res
        previous_err = err
        chord = ev.K is None
        if not chord:
            fac = counted_factorisation(model, ev.K, backend)
            neg = fac.negative_pivots
        # Both right-hand sides in one pass (b also gives the volume-control stability
        # under pressure control, solver/stability.py, and the path's tangent).
        a, b = counted_solve(model, fac, np.column_stack((-ev.R, ev.g))).T
        solves += 1
        gb = float(ev.g @ b)
        ev_solved = ev
        if target_volume is None:
            du, dp = a, 0.0
        else:
            if gb == 0.0 or not np.isfinite(gb):
                raise StepFailed("bordered system singular (g^T K^-1 g = 0)")
            dp = -(ev.volume_mm3 - target_volume + float(ev.g @ a)) / gb
            du = a + b * dp
        dq = model.pressure_update(ev, du)
        # (An update from a converged start is a whole load step: never a chord.)
        want_tangent = err >= CHORD_SWITCH or (it == 1 and start is not None)
    raise StepFailed(f"no convergence in {settings.max_newton_iter} Newton iterations "
                      f"(residual {res:.2e})")


def newton_step(model: ActuatorModel, u: np.ndarray, p: float, settings: SolverSettings,
                target_volume: float | None, target_pressure: float | None, backend: str):
    """Converge one load step from (u, p); returns (u, p, iterations, residual, negative
    pivots). The element pressures start consistent with u (see ``mixed_newton_step``)."""
    out = mixed_newton_step(model, u, model.consistent_pressures(u), p, settings,
                            target_volume, target_pressure, backend)
    return out.u, out.pressure_pa, out.iterations, out.residual, out.negative_pivots
