"""The start of each load step: the Hermite polynomial through the last converged states
and the equilibrium path's tangent at each, extrapolated to the new load.

The tangent (``Rate``: du/dV = K^-1 g / g^T K^-1 g under volume control, du/dp = K^-1 g
under pressure control) comes from the second right-hand side of the state's last linear
solve (``path_rate``), so it costs no extra factorisation. With three states and their
tangents the polynomial is a quintic; with one state and its tangent, the Euler
predictor. On the standard curve it starts ~10x closer to the converged state than the
parabola through the states alone, and most steps converge after two Newton solves
(benchmarks/RESULTS.md, issue 12). The load parameter is the cavity volume (mm^3) under
volume control, the pressure (Pa) under pressure control; displacements in mm, element
and cavity pressures in Pa.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.discrete import ActuatorModel, Evaluation

PREDICTOR_POINTS = 3        # converged states (with their tangents) the predictor passes through


@dataclass
class Rate:
    """The tangent of the equilibrium path at a state, per unit of the load parameter
    (cavity volume in mm^3 under volume control, pressure in Pa under pressure control):
    displacement (mm), element pressures (Pa) and cavity pressure (Pa)."""

    du: np.ndarray
    dq: list[np.ndarray]
    dp: float


@dataclass
class State:
    """A converged state on the path at load parameter ``load`` (see ``Rate``), with its
    rate when known: what the predictor extrapolates from."""

    load: float
    u: np.ndarray
    q: list[np.ndarray]
    pressure_pa: float
    rate: Rate | None = None


def path_rate(model: ActuatorModel, ev: Evaluation, b: np.ndarray, g_kinv_g: float,
              volume_control: bool) -> Rate | None:
    """The equilibrium path's tangent from b = K^-1 g (the second right-hand side of the
    last linear solve, at an iterate next to the converged state): under pressure
    control du/dp = b; under volume control, where K du = g dp and g . du = dV,
    du/dV = b / (g . b) and dp/dV = 1 / (g . b). None if g . b is not usable."""
    if not np.isfinite(g_kinv_g) or g_kinv_g == 0.0:
        return None
    scale = 1.0 / g_kinv_g if volume_control else 1.0
    du = b * scale
    return Rate(du, model.pressure_update(ev, du, constraint=False), scale)


def extrapolation_weights(loads: np.ndarray, has_rate: np.ndarray, load: float
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Weights (w, w') of the Hermite polynomial through values at ``loads`` and, where
    ``has_rate``, their first derivatives, evaluated at ``load``: value = sum w f +
    sum w' f'. Its degree is the number of conditions less one (a confluent
    Vandermonde system in the load scaled to the points' spread)."""
    origin = float(loads[-1])
    scale = max(float(np.abs(loads - origin).max()), abs(load - origin), 1e-300)
    x = (loads - origin) / scale
    rows, kinds = [], []
    degree = len(loads) + int(has_rate.sum())
    k = np.arange(degree)
    for i, xi in enumerate(x):
        rows.append(xi ** k)
        kinds.append((i, False))
        if has_rate[i]:
            rows.append(k * xi ** np.maximum(k - 1, 0) / scale)   # d/d(load) of x^k
            kinds.append((i, True))
    target = ((load - origin) / scale) ** k
    w = np.linalg.solve(np.array(rows).T, target)
    values, rates = np.zeros(len(loads)), np.zeros(len(loads))
    for weight, (i, is_rate) in zip(w, kinds):
        (rates if is_rate else values)[i] = weight
    return values, rates


def predictor(history: list[State], load: float
              ) -> tuple[np.ndarray, list[np.ndarray], float] | None:
    """Extrapolated start (u, q, p) for the next step at load parameter ``load`` (the
    cavity volume under volume control, the pressure under pressure control): the
    Hermite polynomial through the last converged states and their path tangents
    (``Rate``; quintic through three states with tangents: ~10x closer to the
    converged state than the parabola through the states alone, benchmarks/RESULTS.md),
    or None with a single state that has no tangent (the step then starts from the
    converged state with its tangent: an Euler predictor)."""
    has_rate = np.array([h.rate is not None for h in history])
    if len(history) + int(has_rate.sum()) < 2:
        return None
    w, wr = extrapolation_weights(np.array([h.load for h in history]), has_rate, load)

    rates = [h.rate for h in history]

    def combine(values: list, rate_values: list):
        out = sum(wi * v for wi, v in zip(w, values))
        return out + sum(wi * r for wi, r in zip(wr, rate_values) if r is not None)

    u = combine([h.u for h in history], [r and r.du for r in rates])
    q = [combine([h.q[b] for h in history], [r and r.dq[b] for r in rates])
         for b in range(len(history[0].q))]
    p = float(combine([h.pressure_pa for h in history], [r and r.dp for r in rates]))
    return u, q, p
