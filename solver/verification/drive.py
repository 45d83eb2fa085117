"""Drive a generic ``SolidModel`` through prescribed volumes or pressures.

Uses the solver's own ``newton_step`` (the production Newton loop, bordered system
under volume control) so that the verification exercises the code the product
runs; only the stepping is simpler: fixed increments, halved on failure.
``drive_pressure`` also starts each increment from the production predictor
(``solver.hermite_predictor.predictor``; from the last converged state if that start fails), as
the felupe benchmark compares the two codes' solves at the same increments.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from solver.errors import ConvergenceError
from solver.hermite_predictor import PREDICTOR_POINTS, State, predictor
from solver.newton import StepFailed, mixed_newton_step, newton_step
from solver.settings import SolverSettings


def drive_volume(model, volumes_mm3: Sequence[float], settings: SolverSettings | None = None,
                 substeps: int = 1, max_cutbacks: int = 6, backend: str = "auto"
                 ) -> tuple[list[tuple[float, float, int]], np.ndarray]:
    """Converge at each cavity volume in turn (mm^3, the model's own, e.g. half volume).

    Each interval is split into ``substeps`` equal increments (halved on failure).
    Returns ([(volume_mm3, pressure_pa, newton_iterations)] at the requested volumes,
    final free displacement). Raises ConvergenceError if a step cannot converge.
    """
    settings = settings or SolverSettings()
    u = np.zeros(model.n_free)
    p = 0.0
    v = model.volume0_mm3
    out = []
    for target in volumes_mm3:
        its_total = 0
        inc = (target - v) / substeps
        cut = 0
        while v != target:
            vt = target if abs(target - v) <= abs(inc) * (1 + 1e-12) else v + inc
            try:
                u, p, its, _, _ = newton_step(model, u, p, settings, vt, None, backend)
            except (StepFailed, FloatingPointError) as exc:
                cut += 1
                if cut > max_cutbacks:
                    raise ConvergenceError(f"volume step to {vt:.6g} mm^3 failed: {exc}"
                                           ) from None
                inc *= 0.5
                continue
            v = vt
            cut = 0
            its_total += its
        out.append((v, p, its_total))
    return out, u


def drive_pressure(model, pressures_pa: Sequence[float], settings: SolverSettings | None = None,
                   max_cutbacks: int = 6, backend: str = "auto"
                   ) -> list[tuple[np.ndarray, int]]:
    """Converge at each prescribed cavity pressure (Pa) in turn, from the undeformed state.

    A failed increment is halved (up to ``max_cutbacks`` times in a row). Returns
    [(free displacement, newton_iterations)] at the requested pressures; raises
    ConvergenceError if an increment cannot converge.
    """
    settings = settings or SolverSettings()
    u = np.zeros(model.n_free)
    p = 0.0
    history = [State(0.0, u, model.consistent_pressures(u), 0.0)]
    out = []
    for target in pressures_pa:
        its_total = 0
        inc = target - p
        cut = 0
        extrapolate = True
        while p != target:
            pt = target if abs(target - p) <= abs(inc) * (1 + 1e-12) else p + inc
            guess = predictor(history, pt) if extrapolate else None
            u0, q0, p0 = guess if guess is not None else (u, model.consistent_pressures(u), p)
            try:
                step = mixed_newton_step(model, u0, q0, p0, settings, None, pt, backend)
            except (StepFailed, FloatingPointError) as exc:
                if guess is not None:
                    extrapolate = False          # retry from the converged state
                    continue
                extrapolate = True
                cut += 1
                if cut > max_cutbacks:
                    raise ConvergenceError(f"pressure step to {pt:.6g} Pa failed: {exc}"
                                           ) from None
                inc *= 0.5
                continue
            u, p = step.u, pt
            history = (history + [State(pt, u, step.q, pt, step.rate)])[-PREDICTOR_POINTS:]
            extrapolate = True
            cut = 0
            its_total += step.iterations
        out.append((u.copy(), its_total))
    return out
