"""Inverse design over the box, for any Predictor: which design meets a target, ranked.

    result = search_designs(model, DesignTarget("angle_at_pressure", 1500, 45),
                            SearchBounds(L_mm=(4, 12)), objective="certainty")

Search space: L, t, T, b, h within the user's bounds (default: the box of
``solver.design_space``), the allowed material pairs (default: all four) and each layer's
stiffness scale (default 1: the presets as sold; give bounds to search them too). A
model that covers only slices of the box (the exponential model: fixed T, b, h per
family) lists them with ``covered_slices()``; the search then pins those values.

Method: 512 scrambled Sobol candidates per pair (log-uniform in every bound), each
evaluated by the model's own inverse (the pressure that gives the target angle) or
forward prediction (force); a syringe pump's target (angle_at_volume, volume_budget,
angle_at_time, time_budget: surrogate/search/pump_targets.py) by the model's answers by injected
volume instead (the volume that gives the target angle, the angle at the target volume;
time = volume / flow). For targets hit exactly (at a pressure, volume or time), the
best candidates are then solved by bisection so that the target is met to 1 %: along the
chamber length, or, where the user pins it (a fixed mould), along the first free one of
t, the membrane's stiffness scale, h, b, T and the body's stiffness scale (KNOBS).
Ranking (lower score first):

    pressure    pressure needed (pressure_budget)
    volume      injected volume needed (volume_budget, time_budget)
    margin      the band's upper end of the pressure (or volume) needed
    compact     chamber length L
    certainty   the band's width relative to the value at the target pressure (volume)

Candidates closer than MIN_SPACING (unit-cube distance) to a better one are dropped.

The parts, one module each: the searched space and its candidates
(``surrogate.search.space``), the screen (``surrogate.search.screen``), the solve to an
exact target (``surrogate.search.solve_to_target``), the ranking (``surrogate.search.ranking``),
a listed design's sensitivity to a mould's tolerance (``surrogate.search.mould_tolerance``) and
the explanation when none is listed (``surrogate.search.explanations``); this module runs
them in order.

The target's sign is the bending direction asked for: a positive angle (or force) bends
away from the membrane (PDMS bodies), a negative one towards it (the reversed pair, and
Ecoflex / Ecoflex designs on either side of their stiffness balance). Designs that bend
the other way are not candidates; when none bends the way asked, the explanation says
what the other direction reaches. The same SOLVED_PER_PAIR candidates are solved whatever
``n_results`` is, so the first k of n results are the k best (a search for 3 had solved
fewer and missed the best of a search for 5, and one for 5 that of one for 20).
"""

from __future__ import annotations

import threading

import numpy as np

from solver.errors import InputError
from surrogate.band_level import z_value
from surrogate.errors import stop_if_cancelled
from surrogate.search.design_result import DesignCandidate, InverseDesignResult
from surrogate.search.design_target import DesignTarget, resolve_objective
from surrogate.search.explanations import (
    SearchSeen,
    no_design_explanation,
    passed_over_note,
    stretch_hazard_note,
    unanswered_error,
)
from surrogate.search.mould_tolerance import change_per_tolerance
from surrogate.search.pump_targets import (
    ask,
    no_volume_error,
    require_volumes,
    volume_report,
)
from surrogate.search.ranking import rank, score
from surrogate.search.screen import Screened, keep_direction, screen, target_direction
from surrogate.search.solve_to_target import BISECTION_STEPS, solve_along, solve_variable
from surrogate.search.space import (
    CANDIDATES_PER_PAIR,
    SearchBounds,
    candidate_design,
    sobol_candidates,
)

#: designs returned at most (the HTTP schema and the CLI read it)
N_RESULTS_MAX = 20
#: candidates per pair, nearest the target, solved exactly to it: 6 per result of the
#: largest answer, whatever n_results is (30 found a best design of score 0.0107 where
#: 120 found 0.0085, for 30 deg at 1500 Pa over the box: 1.4 -> 3.1 s on one thread)
SOLVED_PER_PAIR = 6 * N_RESULTS_MAX
#: points of each listed design's curve, from 0 to the target (or needed) pressure (volume)
CURVE_POINTS = 41


def search_designs(model: object, target: DesignTarget, bounds: SearchBounds,
                   objective: str | None = None, n_results: int = 5, level: float = 0.95,
                   seed: int = 0, cancel: threading.Event | None = None
                   ) -> InverseDesignResult:
    """Ranked designs meeting ``target`` (see the module docstring). ``cancel``: set by
    another thread, the search stops at its next batch of designs (a pair's screen, a
    bisection step, a candidate asked back) with ``surrogate.errors.Cancelled``."""
    z_value(level)   # a level outside 0.5..1 (NaN) is refused, not searched as "unreachable"
    target = target.validated()
    if target.by_volume:
        require_volumes(model, target)
    objective = resolve_objective(target, objective)
    ranges = bounds.ranges()
    slices_fn = getattr(model, "covered_slices", None)
    if not 1 <= n_results <= N_RESULTS_MAX:
        raise InputError("n_results", f"got {n_results}", f"1 <= n_results <= {N_RESULTS_MAX}")
    direction = target_direction(target)
    n_evaluated = 0
    seen = SearchSeen()
    feasible: list[Screened] = []
    for pair in bounds.allowed_pairs():
        stop_if_cancelled(cancel)
        slices = slices_fn(pair) if slices_fn is not None else None
        if slices is not None and not slices:
            continue
        designs, kept = [], []
        count = (CANDIDATES_PER_PAIR if hasattr(model, "evaluate_designs")
                 else CANDIDATES_PER_PAIR // 4)   # one predict per design: fewer
        for values in sobol_candidates(ranges, slices, seed, count):
            try:
                designs.append(candidate_design(pair, values))
                kept.append(values)
            except InputError:
                continue
        if not designs:
            continue
        r = screen(model, designs, target, level)
        n_evaluated += len(designs)
        seen.note_screen(designs, r, direction)
        keep_direction(r, direction)
        evals = [Screened.from_screen(pair, v, d, r, i)
                 for i, (v, d) in enumerate(zip(kept, designs)) if np.isfinite(r["value"][i])
                 or np.isfinite(r["needed"][i])]
        if not evals:
            continue
        reachable = [e for e in evals if np.isfinite(e.value)]
        seen.note_reach(pair, reachable, direction, _where(target))
        if target.budget:
            feasible += [e for e in evals if np.isfinite(e.needed) and e.needed <= target.at]
            continue
        # exact targets: the candidates nearest the target, then solved along a variable
        near = sorted(reachable, key=lambda e: abs(np.log(max(e.value, 1e-12) / target.value)))
        knob = solve_variable(ranges)
        if knob is None:            # every variable pinned: the one design, if it hits
            feasible += [e for e in near[:1] if abs(e.value - target.value)
                         <= 0.01 * target.value]
            continue
        solved = near[:SOLVED_PER_PAIR]
        hits = solve_along(model, solved, target, level, knob, ranges[knob], cancel)
        n_evaluated += (BISECTION_STEPS + 3) * len(solved)
        feasible += hits
    refused = unanswered_error(model, target, seen, bool(feasible))
    if refused is not None:
        raise refused
    if seen.no_volume and not seen.best_reach and not feasible:
        raise no_volume_error(model, target)
    feasible, chosen, near_copies, not_as_screened = rank(
        model, feasible, target, objective, ranges, n_results, level, cancel)
    candidates = [_listed(model, rank_, e, target, objective, direction, level, cancel)
                  for rank_, e in enumerate(chosen, 1)]
    if candidates:
        explanation = (f"{len(feasible)} of {n_evaluated} evaluated designs meet the target; "
                       f"the {len(candidates)} best by {objective} are listed"
                       + passed_over_note(len(candidates), n_results, near_copies,
                                          not_as_screened)
                       + stretch_hazard_note(candidates))
    else:
        explanation = no_design_explanation(model, target, seen, ranges, level, direction,
                                            cancel)
    clipped = bounds.clipped(ranges)
    if clipped:
        explanation += ("; searched within the emulator's box: " + ", ".join(clipped))
    return InverseDesignResult(target=target, objective=objective,
                               feasible=bool(candidates), candidates=tuple(candidates),
                               explanation=explanation, best_reachable=seen.best_reach,
                               n_evaluated=n_evaluated)


def _listed(model: object, rank_: int, e: Screened, target: DesignTarget, objective: str,
            direction: float, level: float, cancel: threading.Event | None
            ) -> DesignCandidate:
    """The ``rank_``-th listed design: its curve to the target, the value where it meets
    the target with its band (signed the way asked), the pressure it needs (a pump's
    target: with the volume and time needed), and its sensitivity to a mould's
    tolerance."""
    stop_if_cancelled(cancel)
    # the curve from 0 Pa (0 ul) to the target pressure (volume; a budget's: to where
    # the design meets the angle -- drawn to the budget it reached past the FE's
    # range, and every recommended design was flagged past_fe_range)
    top = (e.needed if target.budget and np.isfinite(e.needed)
           else max(target.at, e.needed if np.isfinite(e.needed) else 0.0))
    curve = ask(model, e.design, target, np.linspace(0.0, top, CURVE_POINTS), level)
    value, value_lo, value_hi = e.value, e.value_lo, e.value_hi
    if target.kind == "pressure_budget":
        # the angle where the design meets the target, at the pressure needed (at the
        # budget itself it may lie past the design's FE range: no answer there)
        at = model.predict(e.design, [e.needed], level=level)  # type: ignore
        value, value_lo, value_hi = (abs(float(at.angle_deg[0])),
                                     *sorted(abs(float(v[0])) for v in
                                             (at.lower_deg, at.upper_deg)))
    # the search matched magnitudes of the direction asked: the sign put back
    lo, hi = (value_lo, value_hi) if direction > 0 else (-value_hi, -value_lo)
    at_where = e.needed if target.budget else target.at
    needed = (e.needed, e.needed_lo, e.needed_hi)
    pump = {}
    if target.by_volume:
        # a pump's target: the volume needed is reported as such (volume_report), the
        # pressure needed for the angle by the model's inverse; no target pressure
        inv = model.inverse(e.design, [direction * target.value],  # type: ignore
                            level=level)
        pump = volume_report(model, e.design, target, inv, level, curve.validity)
        needed = (float(inv.pressure_pa[0]), float(inv.lower_pa[0]),
                  float(inv.upper_pa[0]))
        value = lo = hi = np.nan
    return DesignCandidate(
        rank=rank_, design=e.design, family="/".join(e.pair),
        score=float(score(e, objective)), pressure_needed_pa=needed[0],
        pressure_lower_pa=needed[1], pressure_upper_pa=needed[2],
        value_at_pressure=direction * value, value_lower=lo, value_upper=hi,
        curve=curve, change_per_0_01_mm=change_per_tolerance(model, e.design, target,
                                                             at_where, level), **pump)


def _where(target: DesignTarget) -> dict[str, float]:
    """Where ``best_reachable`` was read: at the target pressure (Pa), or at the pump's
    volume (ul) and time (s)."""
    if not target.by_volume:
        return {"at_pressure_pa": float(target.at)}
    out = {"at_volume_ul": float(target.at)}
    if target.time_s is not None:
        out["at_time_s"] = float(target.time_s)
    return out
