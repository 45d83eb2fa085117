"""Leaving an unstable equilibrium branch under volume control (issue 12).

Two situations, two methods.

**A bifurcation passed** (a converged state unstable at constant volume,
``switch_branch``). The primary solution (the branch continued from the undeformed
state) is then a saddle of the potential Pi = E - p (V - V_t) at constant volume: along
its unstable volume-neutral mode phi (solver/stability.py) Pi decreases, and the stable
secondary branch lies that way, at a distance that grows like the square root of the
volume past a pitchfork. Newton alone cannot leave the primary branch: started from a
small perturbation it converges back to the nearest equilibrium, the unstable one. The
secondary branch is reached by continuation in the mode's amplitude:

1. phi: the lowest eigenvector of K on the volume-neutral subspace at the state;
2. at the target volume, equilibrium with the amplitude s = phi . (u - u_0) prescribed
   as a second constraint, its multiplier f the force along phi that holds s
   (grad Pi = f phi; Newton on the doubly bordered system, ``amplitude_newton``);
3. s is stepped away from 0 in the direction in which Pi falls (f s < 0) until f
   changes sign: there dPi/ds = 0 with Pi at a minimum along the path, an
   equilibrium off the primary branch. The amplitude constraint is released (plain
   volume-controlled Newton from that state) and the result is kept when it is stable
   at constant volume and, at the same volume, has a lower potential than the state
   it left.

**A fold in volume** (a volume step fails however far it is cut back, ``pass_fold``).
An imperfect pitchfork (the actuator is not symmetric along x: one end clamped) turns
the bifurcation into a path that reaches a maximum of the volume and turns back: the
bordered system is singular there and there is no equilibrium nearby beyond it (under
a syringe pump, a snap). Arc-length continuation in u (the bordered matrix
[[K, -g], [t^T, 0]] stays regular at folds in pressure and in volume) follows the path
over the fold, back along the branch that is unstable at constant volume, until it is
stable again at or beyond the failed step's volume; a volume step to that volume from
there is the new state.

What did not work (kept out): a line search of Pi along +-s phi at fixed pressure
followed by Newton at the same volume. On two balloons sharing one pressure
(solver/verification/two_balloons.py) the line minimum lies at 0.005-0.03 mm, because
the frozen mode's second-order dilatation times the bulk modulus dominates Pi, and
Newton from there returned to the symmetric state every time (potential drop 1e-12 nJ);
on the actuator (t = 0.25 mm) the mode injected at 0.01-0.16 mm at a failed step did
not converge from any of six starts, and the amplitude-held Newton at the failed
step's volume (step 2 above) did not converge either (residual 2.2 after 15
iterations): past a fold there is no nearby state to hold.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from solver.discrete import ActuatorModel
from solver.linear import factorize
from solver.stability import constrained_modes, volume_control_index

FIRST_STEP = 0.01       # first amplitude increment, x the state's largest displacement
GROWTH = 1.6            # increment growth after a step converged in <= EASY_ITERATIONS
EASY_ITERATIONS = 4
MAX_AMPLITUDE = 2.0     # give up beyond this amplitude, x the state's largest displacement
MIN_STEP = 1e-4         # give up when an increment is cut below this (same unit)
MODE_NEWTON_ITER = 15
ARC_FIRST_STEP = 1e-4   # first arc-length step, x the norm of the state's displacement
ARC_MAX_STEP = 0.02     # largest arc-length step (same unit)
ARC_MIN_STEP = 1e-7     # give up when a step is cut below this (same unit)
ARC_STEPS = 100         # arc-length steps before giving up
ARC_EASY_ITERATIONS = 3  # an arc-length step converged in this many grows the next,
                         # in more than EASY_ITERATIONS halves it
ARC_MAX_ITERATIONS = 6   # an arc-length step converged in more is retried at half the size


@dataclass
class Switch:
    """Outcome of a switch attempt; ``converged`` is the new state (a stepping
    ``Converged``) when accepted, else None; ``reason`` says why not.
    ``amplitude_mm``: the largest nodal displacement of the mode's amplitude at the
    release; ``potential_drop``: Pi of the state left minus Pi of the new one at the
    target volume (nJ; when the state left is at another volume, its Pi there to first
    order in the difference)."""

    converged: object | None
    eigenvalue: float
    amplitude_mm: float
    potential_drop: float
    reason: str


@dataclass
class ModeState:
    """An equilibrium at fixed cavity volume with the mode's amplitude held by a force
    ``force`` (uN) along phi: grad Pi = force phi, phi . (u - u_0) = amplitude."""

    u: np.ndarray
    q: list[np.ndarray]
    pressure_pa: float
    force: float
    amplitude: float
    iterations: int


def potential(model: ActuatorModel, u: np.ndarray, p: float, target_volume: float) -> float:
    """Pi = E - p (V - V_t) of the penalty form at (u, p) (nJ): the function whose
    minimum at constant volume is the stable state."""
    ev = model.evaluate(u, p, tangent=False)
    return ev.energy - p * (ev.volume_mm3 - target_volume)


def lowest_volume_neutral_mode(model: ActuatorModel, u: np.ndarray, q: list[np.ndarray],
                               p: float, backend: str) -> tuple[float, np.ndarray]:
    """The lowest eigenvalue of K on the volume-neutral subspace at (u, q, p), uN/mm,
    and its unit eigenvector."""
    ev = model.evaluate(u, p, pressures=q)
    vals, vecs = constrained_modes(ev.K, ev.g, factorize(ev.K, backend), k=1)
    return float(vals[0]), vecs[:, 0]


def amplitude_newton(model: ActuatorModel, start: ModeState, u0: np.ndarray, phi: np.ndarray,
                     amplitude: float, target_volume: float, tol: float, backend: str
                     ) -> ModeState:
    """Newton on equilibrium with two constraints, the cavity volume and the amplitude
    phi . (u - u0) (phi a unit vector), the pressure and the force along phi their
    multipliers; one factorisation of K and three back-substitutions per iteration.
    Raises ArithmeticError if it does not converge to ``tol`` (as the stepping's)."""
    u, q, p, force = start.u, start.q, start.pressure_pa, start.force
    volume_scale = max(model.volume0_mm3, 1e-9)
    force_floor = model.mu0_min_pa * 1e-6
    res = np.inf
    for it in range(1, MODE_NEWTON_ITER + 1):
        ev = model.evaluate(u, p, pressures=q)
        r = ev.R - force * phi
        res = float(np.linalg.norm(r)) / max(ev.load_norm, force_floor)
        dv = ev.volume_mm3 - target_volume
        ds = float(phi @ (u - u0)) - amplitude
        if not np.isfinite(res):
            raise ArithmeticError("non-finite residual")
        if (it > 1 and res < tol and abs(dv) < tol * volume_scale
                and ev.constraint_error < tol):
            return ModeState(u, q, p, force, amplitude, it - 1)
        a, b, c = factorize(ev.K, backend).solve(np.column_stack((-r, ev.g, phi))).T
        # du = a + dp b + df c with g . du = -dv and phi . du = -ds
        border = np.array([[ev.g @ b, ev.g @ c], [phi @ b, phi @ c]])
        dp, df = np.linalg.solve(border, [-dv - ev.g @ a, -ds - phi @ a])
        du = a + dp * b + df * c
        q = [qb + d for qb, d in zip(q, model.pressure_update(ev, du))]
        u, p, force = u + du, p + dp, force + df
    raise ArithmeticError(f"no convergence in {MODE_NEWTON_ITER} iterations (residual "
                          f"{res:.2e})")


def mode_continuation(model: ActuatorModel, start: ModeState, u0: np.ndarray,
                      phi: np.ndarray, target_volume: float, sign: float, scale_mm: float,
                      tol: float, backend: str) -> ModeState | None:
    """From ``start`` (an amplitude-constrained equilibrium at ``target_volume``), step
    the amplitude of phi in the direction ``sign`` until the force holding it, after
    pointing against the step (Pi falling), vanishes; return the first state past that
    sign change, or None (increments below MIN_STEP, or the amplitude beyond
    MAX_AMPLITUDE, both in units of ``scale_mm`` of the largest nodal displacement)."""
    unit = scale_mm / float(np.abs(phi).max())       # amplitude of phi per scale_mm
    step = FIRST_STEP * unit * sign
    state = start
    falling = start.force * sign < 0
    while abs(state.amplitude - start.amplitude) < MAX_AMPLITUDE * unit:
        try:
            new = amplitude_newton(model, state, u0, phi, state.amplitude + step,
                                   target_volume, tol, backend)
        except (ArithmeticError, FloatingPointError, np.linalg.LinAlgError, RuntimeError):
            step *= 0.5
            if abs(step) < MIN_STEP * unit:
                return None
            continue
        if new.force * sign < 0:
            falling = True
        elif falling:
            return new
        state = new
        if new.iterations <= EASY_ITERATIONS:
            step *= GROWTH
    return None


def switch_branch(model: ActuatorModel, u: np.ndarray, q: list[np.ndarray], p: float,
                  target_volume: float, converge: Callable, backend: str, tol: float,
                  at_target: bool) -> Switch:
    """Leave the branch of the converged state (u, q, p) for a stable equilibrium at
    cavity volume ``target_volume`` (half model, mm^3) by continuation in the amplitude
    of its lowest volume-neutral mode (module docstring). ``at_target``: the state is
    at ``target_volume`` and unstable there (a bifurcation passed); otherwise it is the
    last converged state before a volume step to ``target_volume`` failed.
    ``converge(u, q, p)`` runs the volume-controlled Newton step to ``target_volume``
    from a start and returns a stepping ``Converged``."""
    eigenvalue, phi = lowest_volume_neutral_mode(model, u, q, p, backend)
    if at_target and eigenvalue >= 0:
        return Switch(None, eigenvalue, 0.0, 0.0, "no volume-neutral negative eigenvalue")
    scale_mm = max(float(np.abs(u).max()), 1e-3)
    try:
        start = amplitude_newton(model, ModeState(u, q, p, 0.0, 0.0, 0), u, phi, 0.0,
                                 target_volume, tol, backend)
    except (ArithmeticError, FloatingPointError, np.linalg.LinAlgError, RuntimeError) as exc:
        return Switch(None, eigenvalue, 0.0, float("nan"),
                      f"no equilibrium with the mode held at the target volume: {exc}")
    # Pi at the target volume of the state left (at another volume: to first order).
    base = potential(model, u, p, target_volume)
    # At a bifurcation passed the force is ~0 and either side falls; past a fold only the
    # side against the force does.
    held = abs(start.force) > tol * max(model.evaluate(u, p, tangent=False).load_norm,
                                        model.mu0_min_pa * 1e-6)
    signs = (-float(np.sign(start.force)),) if held else (1.0, -1.0)
    tried = []
    for sign in signs:
        found = mode_continuation(model, start, u, phi, target_volume, sign, scale_mm, tol,
                                  backend)
        if found is None:
            tried.append(f"side {sign:+.0f}: no zero of the holding force")
            continue
        try:
            out = converge(found.u, found.q, found.pressure_pa)
        except Exception as exc:    # StepFailed, an inverted element, a failed factorisation
            tried.append(f"side {sign:+.0f}: released Newton failed ({exc})")
            continue
        index = volume_control_index(out.negative_pivots, out.g_kinv_g)
        drop = base - potential(model, out.u, out.pressure_pa, target_volume)
        amplitude_mm = abs(float(phi @ (out.u - u))) * float(np.abs(phi).max())
        if index != 0 or drop <= 0.0:
            tried.append(f"side {sign:+.0f}: an equilibrium with {index} unstable modes, "
                         f"potential drop {drop:.3g} nJ")
            continue
        return Switch(out, eigenvalue, amplitude_mm, drop,
                      f"switched (lowest volume-neutral eigenvalue {eigenvalue:.3g} uN/mm, "
                      f"mode amplitude {amplitude_mm:.3g} mm, potential drop {drop:.3g} nJ)")
    return Switch(None, eigenvalue, 0.0, float("nan"),
                  f"no stable state along the lowest volume-neutral mode (eigenvalue "
                  f"{eigenvalue:.3g} uN/mm): " + "; ".join(tried))


@dataclass
class PathPoint:
    """A converged state of the arc-length continuation with its stability and the
    path's unit tangent (du, dp) per unit arc length in u."""

    u: np.ndarray
    q: list[np.ndarray]
    pressure_pa: float
    volume_mm3: float
    unstable_modes: int
    tangent_u: np.ndarray
    tangent_p: float
    iterations: int


def arc_length_point(model: ActuatorModel, start: PathPoint, step: float, tol: float,
                     backend: str) -> PathPoint:
    """One arc-length step along the equilibrium path R(u, p) = 0 from ``start``: the
    predictor start + step x tangent, then Newton with the constraint
    t_u . (u - u_start) = step (cylindrical arc length in u: the bordered matrix
    [[K, -g], [t_u^T, 0]] stays regular at folds in pressure and in volume)."""
    t_u = start.tangent_u
    u, p = start.u + step * t_u, start.pressure_pa + step * start.tangent_p
    q = start.q
    force_floor = model.mu0_min_pa * 1e-6
    res = np.inf
    for it in range(1, MODE_NEWTON_ITER + 1):
        ev = model.evaluate(u, p, pressures=q)
        res = float(np.linalg.norm(ev.R)) / max(ev.load_norm, force_floor)
        c = float(t_u @ (u - start.u)) - step
        if not np.isfinite(res):
            raise ArithmeticError("non-finite residual")
        fac = factorize(ev.K, backend)
        a, b = fac.solve(np.column_stack((-ev.R, ev.g))).T
        if it > 1 and res < tol and ev.constraint_error < tol and abs(c) < tol * abs(step):
            gkg = float(ev.g @ b)
            # The tangent: K du = g dp, oriented along the step just made (the secant;
            # the old tangent can point back after a step over a sharp turn).
            du = b / float(np.linalg.norm(b))
            sign = 1.0 if du @ (u - start.u) >= 0 else -1.0
            return PathPoint(u, q, p, ev.volume_mm3,
                             volume_control_index(fac.negative_pivots, gkg), sign * du,
                             sign / float(np.linalg.norm(b)), it - 1)
        dp = (-c - float(t_u @ a)) / float(t_u @ b)
        du = a + dp * b
        q = [qb + d for qb, d in zip(q, model.pressure_update(ev, du))]
        u, p = u + du, p + dp
    raise ArithmeticError(f"no convergence in {MODE_NEWTON_ITER} iterations (residual "
                          f"{res:.2e})")


def pass_fold(model: ActuatorModel, u: np.ndarray, q: list[np.ndarray], p: float,
              target_volume: float, converge: Callable, backend: str, tol: float,
              log: list | None = None) -> Switch:
    """A volume step from the converged state (u, q, p) to ``target_volume`` failed at
    a fold of the path in volume (the bordered system singular, no equilibrium nearby
    beyond it: under a syringe pump, a snap). Follow the equilibrium path by arc length
    from the state, over the fold and along the branch beyond it (unstable at constant
    volume), until it is stable at constant volume again at a volume at or beyond
    ``target_volume``; then converge the volume step there."""
    ev = model.evaluate(u, p, pressures=q)
    fac = factorize(ev.K, backend)
    b = fac.solve(ev.g)
    gkg = float(ev.g @ b)
    # Start towards growing volume: dV = g . du = gkg dp.
    sign = 1.0 if gkg > 0 else -1.0
    point = PathPoint(u, q, p, ev.volume_mm3, volume_control_index(fac.negative_pivots, gkg),
                      sign * b / float(np.linalg.norm(b)), sign / float(np.linalg.norm(b)), 0)
    scale = max(float(np.linalg.norm(u)), 1e-3)
    step = ARC_FIRST_STEP * scale
    left = False
    volumes = [point.volume_mm3]
    for _ in range(ARC_STEPS):
        try:
            new = arc_length_point(model, point, step, tol, backend)
        except (ArithmeticError, FloatingPointError, np.linalg.LinAlgError, RuntimeError):
            new = None
        if new is None or new.iterations > ARC_MAX_ITERATIONS:
            # (A hard step may have landed on another part of the path, past a sharp
            # turn, and continued from there backwards: it is not taken.)
            step *= 0.5
            if step < ARC_MIN_STEP * scale:
                break
            continue
        if log is not None:
            log.append((new.volume_mm3, new.pressure_pa, new.unstable_modes, new.iterations))
        volumes.append(new.volume_mm3)
        left = left or new.unstable_modes > 0
        point = new
        if left and new.unstable_modes == 0 and new.volume_mm3 >= target_volume:
            try:
                out = converge(new.u, new.q, new.pressure_pa)
            except Exception as exc:   # StepFailed, an inverted element, a failed factorisation
                return Switch(None, float("nan"), 0.0, float("nan"),
                              f"past the fold, the volume step back to the target failed: {exc}")
            index = volume_control_index(out.negative_pivots, out.g_kinv_g)
            # Pi at the target volume: of the new state, and of the last one before the
            # fold (to first order in its small volume difference).
            drop = (potential(model, u, p, target_volume)
                    - potential(model, out.u, out.pressure_pa, target_volume))
            if index == 0:
                return Switch(out, float("nan"), float(np.abs(out.u - u).max()), drop,
                              f"passed a fold in volume by arc length ({len(volumes) - 1} "
                              f"points, volume {min(volumes):.4g}-{max(volumes):.4g} mm^3, "
                              f"potential drop {drop:.3g} nJ)")
        if new.iterations <= ARC_EASY_ITERATIONS:
            step = min(step * GROWTH, ARC_MAX_STEP * scale)
        elif new.iterations > EASY_ITERATIONS:
            step *= 0.5
    return Switch(None, float("nan"), 0.0, float("nan"),
                  f"arc length from the fold found no stable state at the target volume "
                  f"({len(volumes) - 1} points, volume {min(volumes):.4g}-{max(volumes):.4g} "
                  f"mm^3, left the stable branch: {left})")
