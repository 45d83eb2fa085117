"""Following the stable branch under volume control (``solve(...,
follow_stable_branch=True)``, solver/stepping.py): where the stepping tries to leave the
primary branch, and the attempts (the methods: solver/branching.py).

Two occasions. A converged step whose state is unstable at constant volume has crossed a
bifurcation: the lowest volume-neutral eigenvalue, interpolated linearly in the cavity
volume between the last stable state and this one, locates it, and the switch is made
from a converged primary state ``BIFURCATION_OVERSHOOT`` of the way on from there (the
pump's path leaves the primary branch at the bifurcation), else at the step's own volume.
A step that keeps failing from one converged state (``FAILURES_BEFORE_SWITCH`` attempts)
has met a fold in volume: it is passed by arc length, then along the lowest
volume-neutral mode. Each switch's Newton steps may take ``SWITCH_NEWTON_ITER``
iterations (the mode's amplitude released: the start lies off any equilibrium).
Cavity volumes in mm^3 (the model's), pressures in Pa, eigenvalues in uN/mm.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from solver.branching import Switch, lowest_volume_neutral_mode, pass_fold, switch_branch
from solver.discrete import ActuatorModel
from solver.newton import Converged, StepFailed, mixed_newton_step
from solver.settings import SolverSettings

FAILURES_BEFORE_SWITCH = 6   # follow_stable_branch: failed attempts from one converged state
                             # (extrapolated and plain, each size; the step cut to 1/4) before
                             # the branch switch is tried at the last failed volume
SWITCH_NEWTON_ITER = 12      # Newton iterations allowed when the mode's amplitude is released
BIFURCATION_OVERSHOOT = 0.25  # the switch is made this share of the way from the located
                              # bifurcation to the unstable state that revealed it


def try_switch(model: ActuatorModel, settings: SolverSettings, backend: str,
               state: tuple[np.ndarray, list[np.ndarray], float], volume: float,
               at_target: bool, step_number: int, debug: bool = False) -> Switch:
    """One branch-switch attempt from the converged state (u, q, p) to a stable state at
    the cavity volume ``volume`` (solver/branching.py): along the unstable mode if the
    state is at that volume; otherwise (a failed step) over a fold in volume by arc
    length first, then along the lowest volume-neutral mode. ``step_number``: the curve's
    last converged step, for the debug output."""
    u, q, p = state
    switch_settings = replace(settings, max_newton_iter=SWITCH_NEWTON_ITER)

    def converge(us, qs, ps):
        return mixed_newton_step(model, us, qs, ps, switch_settings, volume, None,
                                 backend, patient=True)
    attempts = ((switch_branch,) if at_target else (pass_fold, switch_branch))
    for attempt in attempts:
        if attempt is switch_branch:
            switch = switch_branch(model, u, q, p, volume, converge, backend,
                                   settings.newton_tol, at_target)
        else:
            switch = pass_fold(model, u, q, p, volume, converge, backend,
                               settings.newton_tol)
        model.timings["branch_switch_attempts"] = (
            model.timings.get("branch_switch_attempts", 0) + 1)
        if debug:
            print(f"branch switch after step {step_number}: {switch.reason}")
        if switch.converged is not None:
            break
    return switch


def near_bifurcation(model: ActuatorModel, settings: SolverSettings, backend: str,
                     a: tuple, b: tuple, volume_a: float, volume_b: float,
                     debug: bool = False) -> tuple[Converged, float] | None:
    """A converged primary state just past the bifurcation crossed between the converged
    states a (stable at constant volume) and b (unstable), each (u, q, p) at the cavity
    volumes ``volume_a`` and ``volume_b``: the lowest volume-neutral eigenvalue
    interpolated linearly in volume to zero, then ``BIFURCATION_OVERSHOOT`` of the way on
    towards b. Returns (Converged, volume), or None if that state does not converge or
    is not unstable."""
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
