"""An exact target met by bisection along one design variable: the search's last step.

An exact target (an angle or force at a pressure, an angle at an injected volume or time)
is rarely met by a screened candidate: the best ones are solved to it along one variable,
the chamber length L (the angle moves about as L does), or where the user pins L (a fixed
mould) along the first free one of ``KNOBS``. Geometric bisection, all candidates at
once, each step one batch screen (``screen.screen``); a candidate counts as a hit
when its value lies within 1 % of the target.
"""

from __future__ import annotations

import threading

import numpy as np

from solver.design import Design
from surrogate.errors import stop_if_cancelled
from surrogate.search.design_target import DesignTarget
from surrogate.search.screen import Screened, keep_direction, screen, target_direction
from surrogate.search.space import candidate_design

# Bisection steps in L: the bracket shrinks to (L_hi / L_lo)^(2^-16), 2.3e-5 of L over the
# whole box (the angle moves about as L does), far inside the 1 % the hit is held to.
BISECTION_STEPS = 16

# The variables an exact target is solved along, in order of preference: the first whose
# bounds are not pinned. The chamber length moves the angle most directly; a lab with a
# fixed mould length still varies the membrane (thickness, then its stiffness).
KNOBS = ("L_mm", "t_mm", "membrane_stiffness_scale", "h_mm", "b_mm", "T_mm",
         "body_stiffness_scale")


def solve_variable(ranges: dict[str, tuple[float, float]]) -> str | None:
    """The variable an exact target is solved along (KNOBS), None when all are pinned."""
    return next((n for n in KNOBS if ranges[n][1] > ranges[n][0]), None)


def solve_along(model: object, evals: list[Screened], target: DesignTarget, level: float,
                name: str, bounds: tuple[float, float],
                cancel: threading.Event | None = None) -> list[Screened]:
    """Bisection along the variable ``name`` within ``bounds`` (all candidates at once,
    geometric) so that the value at the target pressure equals the target; a value past
    the FE's range counts as too large, a design bending the other way as too small (an
    Ecoflex/Ecoflex membrane thick enough to pass the stiffness balance: without it both
    ends of t counted as "too large" and a reachable target was called infeasible).
    Either direction: a candidate is solved when the value minus the target changes sign
    between the bounds. Returns the hits (within 1 % of the target), screened with their
    bands."""
    if not evals:
        return []
    lo = np.full(len(evals), bounds[0])
    hi = np.full(len(evals), bounds[1])

    def f(x: np.ndarray, band: bool = False) -> tuple[np.ndarray, list[Design], dict]:
        designs = [candidate_design(e.pair, {**e.values, name: float(v)})
                   for e, v in zip(evals, x)]
        r = screen(model, designs, target, level, band)
        other_way = keep_direction(r, target_direction(target))     # no hit there
        v = np.where(np.isfinite(r["value"]), r["value"] - target.value, np.inf)
        return np.where(other_way, -np.inf, v), designs, r

    f_lo, _, _ = f(lo)
    f_hi, _, _ = f(hi)
    ok = np.sign(f_lo) != np.sign(f_hi)
    for _ in range(BISECTION_STEPS):
        stop_if_cancelled(cancel)
        mid = np.sqrt(lo * hi)
        f_mid, _, _ = f(mid)
        same = np.sign(f_mid) == np.sign(f_lo)
        lo, f_lo = np.where(same, mid, lo), np.where(same, f_mid, f_lo)
        hi = np.where(same, hi, mid)
    mid = np.sqrt(lo * hi)
    f_mid, designs, r = f(mid, band=True)     # the bands of the designs solved
    return [Screened.from_screen(e.pair, {**e.values, name: float(mid[i])}, designs[i], r, i)
            for i, e in enumerate(evals)
            if ok[i] and np.isfinite(f_mid[i]) and abs(f_mid[i]) <= 0.01 * target.value]
