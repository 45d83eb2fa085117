"""Leaving an unstable equilibrium branch at a bifurcation (eigenvector injection).

Past a bifurcation under volume control the primary (here: symmetric in x about the
chamber's middle, or simply the branch continued from the undeformed state) solution
is a saddle of the potential at constant volume: along the unstable volume-neutral
mode phi (solver/stability.py) the potential Pi = E - p (V - V_t) decreases, and the
stable secondary branch lies on that side. Newton alone cannot leave the primary
branch (it converges to the nearest equilibrium, stable or not), so:

1. phi: the constrained tangent's most negative eigenvector at the converged state;
2. a line search of Pi along +-s phi (s from ``AMPLITUDES_MM``, the largest nodal
   displacement of s phi), keeping the lowest Pi;
3. Newton at the same cavity volume from there. The switch is accepted when Newton
   converges to a state whose potential is lower and which has fewer unstable modes
   at constant volume; otherwise the solve stays on the primary branch.

Near the bifurcation itself the bordered system is singular: a volume step from the
last converged state across it can fail however much it is cut back, before any
converged state shows the negative eigenvalue. ``switch_at_failure`` handles that
case: the lowest volume-neutral mode of the last converged state (whatever its sign),
injected at growing amplitude with both signs, Newton at the failed step's volume; the
first converged state that is stable at constant volume is taken.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from solver.linear import factorize
from solver.model import ActuatorModel
from solver.stability import constrained_modes, volume_control_index

AMPLITUDES_MM = (0.005, 0.01, 0.02, 0.04, 0.08, 0.16)   # trial sizes of the injected mode
FAILURE_AMPLITUDES_MM = (0.01, 0.04, 0.16)   # the same at a failed step (each a Newton solve)


@dataclass
class Switch:
    """Outcome of a switch attempt; ``converged`` is the new state (a stepping
    ``Converged``) when accepted, else None; ``reason`` says why not."""

    converged: object | None
    eigenvalue: float
    amplitude_mm: float
    potential_drop: float
    reason: str


def potential(model: ActuatorModel, u: np.ndarray, p: float, target_volume: float) -> float:
    """Pi = E - p (V - V_t) of the penalty form at (u, p) (nJ): the function whose
    minimum at constant volume is the stable state."""
    ev = model.evaluate(u, p, tangent=False)
    return ev.energy - p * (ev.volume_mm3 - target_volume)


def switch_branch(model: ActuatorModel, u: np.ndarray, q: list[np.ndarray], p: float,
                  target_volume: float, converge: Callable, backend: str) -> Switch:
    """Try to leave the unstable branch at the converged state (u, q, p) of cavity
    volume ``target_volume`` (half model, mm^3). ``converge(u, q, p)`` runs the
    volume-controlled Newton step from a start and returns a ``Converged``."""
    ev = model.evaluate(u, p, pressures=q)
    fac = factorize(ev.K, backend)
    vals, vecs = constrained_modes(ev.K, ev.g, fac, k=1)
    if vals[0] >= 0:
        return Switch(None, float(vals[0]), 0.0, 0.0, "no volume-neutral negative eigenvalue")
    phi = vecs[:, 0] / np.abs(vecs[:, 0]).max()          # largest nodal component 1 mm
    base = potential(model, u, p, target_volume)
    best = (0.0, 0.0)                                     # (drop, signed amplitude)
    for amp in AMPLITUDES_MM:
        for sign in (1.0, -1.0):
            try:
                drop = base - potential(model, u + sign * amp * phi, p, target_volume)
            except FloatingPointError:
                continue
            if drop > best[0]:
                best = (drop, sign * amp)
    if best[0] <= 0.0:
        return Switch(None, float(vals[0]), 0.0, 0.0,
                      "the potential does not fall along the unstable mode")
    start = u + best[1] * phi
    try:
        out = converge(start, perturbed_pressures(model, ev, q, best[1] * phi), p)
    except Exception as exc:         # StepFailed, an inverted element, a failed factorisation
        return Switch(None, float(vals[0]), abs(best[1]), best[0],
                      f"Newton from the perturbed state failed: {exc}")
    drop = base - potential(model, out.u, out.pressure_pa, target_volume)
    index_before = volume_control_index(fac.negative_pivots, float(ev.g @ fac.solve(ev.g)))
    index_after = volume_control_index(out.negative_pivots, out.g_kinv_g)
    if drop <= 0.0 or not (0 <= index_after < index_before):
        return Switch(None, float(vals[0]), abs(best[1]), drop,
                      f"Newton returned to an equilibrium no more stable (potential drop "
                      f"{drop:.3g} nJ, unstable modes {index_before} -> {index_after})")
    return Switch(out, float(vals[0]), abs(best[1]), drop, "switched")


def perturbed_pressures(model: ActuatorModel, ev, q: list[np.ndarray], du: np.ndarray
                        ) -> list[np.ndarray]:
    """Element pressures for the start u + du: q plus their linearised change (the mixed
    iterate's update, solver/assembly.py), not the penalty pressures of the perturbed
    state, whose second-order dilatation times K would swamp the start."""
    return [qb + d for qb, d in zip(q, model.pressure_update(ev, du))]


def mode_component_mm(phi: np.ndarray, du: np.ndarray) -> float:
    """Amplitude of the mode phi (scaled to a largest component of 1) in a displacement
    change du: the least-squares c of du ~ c phi, mm."""
    return float(phi @ du) / float(phi @ phi)


def switch_at_failure(model: ActuatorModel, u: np.ndarray, q: list[np.ndarray], p: float,
                      target_volume: float, converge: Callable, backend: str) -> Switch:
    """A volume step from the converged state (u, q, p) to ``target_volume`` (half
    model, mm^3) failed. Start Newton at ``target_volume`` from u + s phi (phi: the
    lowest volume-neutral mode at (u, q, p), any sign; s from ``FAILURE_AMPLITUDES_MM``, + then
    -) and take the first converged state with no unstable mode at constant volume.
    ``converge(u, q, p)`` runs the volume step to ``target_volume`` from a start.
    ``amplitude_mm`` of the result is the mode's amplitude in the change of state."""
    ev = model.evaluate(u, p, pressures=q)
    fac = factorize(ev.K, backend)
    vals, vecs = constrained_modes(ev.K, ev.g, fac, k=1)
    phi = vecs[:, 0] / np.abs(vecs[:, 0]).max()
    tried = []
    for amp in FAILURE_AMPLITUDES_MM:
        for sign in (1.0, -1.0):
            start = u + sign * amp * phi
            try:
                out = converge(start, perturbed_pressures(model, ev, q, sign * amp * phi), p)
            except Exception as exc:   # StepFailed, an inverted element, a failed factorisation
                tried.append(f"{sign * amp:+g} mm: {type(exc).__name__}")
                continue
            index = volume_control_index(out.negative_pivots, out.g_kinv_g)
            if index == 0:
                return Switch(out, float(vals[0]), abs(mode_component_mm(phi, out.u - u)),
                              float("nan"), f"switched at a failed step (lowest volume-"
                              f"neutral eigenvalue {vals[0]:.3g}; injected {sign * amp:+g} mm)")
            tried.append(f"{sign * amp:+g} mm: converged with {index} unstable modes")
    return Switch(None, float(vals[0]), 0.0, float("nan"),
                  f"no stable state from the injected mode (lowest volume-neutral eigenvalue "
                  f"{vals[0]:.3g}): " + "; ".join(tried))
