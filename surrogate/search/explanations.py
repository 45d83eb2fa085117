"""Why a design search lists no design (or fewer than asked), in words that say what to do.

The screens record what they saw besides the candidates (``SearchSeen``): the designs past
their FE range at the target, the largest value reached, what bends the other way. With no
candidate the explanation names the reason and the remedy, in this order: designs reach
the target but none was solved to it within 1 % (widen the bounds); every design is past
its FE range at the target pressure (ask lower: ``past_range_explanation``); the target
angle lies past the FE's range (``fe_angle_end``); otherwise the target is out of reach
(widen the bounds, or raise the pressure where the force goes on rising:
``force_past_target``). Pressures in Pa, a pump's target's volumes in ul and times in s,
angles in deg, forces in mN.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

import numpy as np

from solver.design import Design
from solver.errors import InputError
from solver.settings import SolverSettings
from surrogate.emulator.stretch_hazard import FLAG as STRETCH_FLAG
from surrogate.emulator.stretch_hazard import HAZARD_STRETCH
from surrogate.errors import stop_if_cancelled
from surrogate.search.design_result import DesignCandidate
from surrogate.search.design_target import DesignTarget
from surrogate.search.pump_targets import ask
from surrogate.search.ranking import MIN_SPACING
from surrogate.search.screen import Screened, keep_direction, screen
from surrogate.search.solve_to_target import solve_variable

#: the bending directions in words (+1, -1)
WAY = {1.0: "away from the membrane (positive angles)",
       -1.0: "towards the membrane (negative angles)"}

# the angle every database curve is solved to (the default solve's angle stop): no
# model fitted from them knows an angle past it
DATABASE_ANGLE_STOP_DEG = SolverSettings().max_angle_deg

#: pressures tried above the target's, as multiples of it (force_past_target)
HIGHER_PRESSURE_FACTORS = tuple(np.round(np.linspace(1.0, 2.0, 41), 3))

#: fractions of the target pressure tried, highest first, for the highest pressure at which
#: designs inside the bounds are still within their FE range (past_range_explanation)
LOWER_PRESSURE_FRACTIONS = (0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1, 0.05)

#: the budget target of each exact angle target (past_range_explanation)
BUDGET_OF = {"angle_at_pressure": "pressure_budget", "angle_at_volume": "volume_budget",
             "angle_at_time": "time_budget"}

#: how to ask for more and for less of a target's axis (the explanations of a target out
#: of reach, and of one past every design's FE range)
MORE_LESS = {"pressure_pa": ("raise the pressure", "lower the pressure (pressure_pa)"),
             "volume_ul": ("inject more (volume_ul)", "inject less (volume_ul)"),
             "time_s": ("pump for longer (time_s)", "pump for less time (time_s)")}


def quantity(target: DesignTarget) -> tuple[str, str]:
    """What ``target`` asks for and its unit: ("force", "mN") or ("angle", "deg")."""
    return ("force", "mN") if target.kind == "force_at_pressure" else ("angle", "deg")


@dataclass
class SearchSeen:
    """What a search's screens saw besides its candidates, for the explanation.

    ``past_range``: per pair, the designs bending the way asked with no number at the
    target (past their FE range); ``past_needed``: the pressures (Pa; a pump's target:
    volumes, ul) they need for the target angle; ``best_reach`` and ``best_design``: the
    largest value reached at the target (signed the way asked, with where it was read)
    and its design; ``other_way``: the largest |value| of the designs bending against the
    target; ``no_force``, ``no_volume``: designs the model answers with no force (a force
    target) or no injected volume (a pump's target)."""

    past_range: list[list[Design]] = field(default_factory=list)
    past_needed: list[float] = field(default_factory=list)
    best_reach: dict[str, object] = field(default_factory=dict)
    best_design: Design | None = None
    other_way: float = 0.0
    no_force: int = 0
    no_volume: int = 0

    def note_screen(self, designs: list[Design], screen_out: dict[str, np.ndarray],
                    direction: float) -> None:
        """A pair's screen (``screen.screen``) before the designs bending against
        ``direction`` are dropped from it."""
        r = screen_out
        # the designs bending the way asked with no number at the target pressure
        is_past = (r["sign"] == direction) & ~np.isfinite(r["value"])
        if np.any(is_past):
            self.past_range.append([d for d, past in zip(designs, is_past, strict=True)
                                    if past])
            self.past_needed += [float(v) for v in r["needed"][is_past] if np.isfinite(v)]
        self.no_force += int(np.sum(r.get("no_force", False)))
        self.no_volume += int(np.sum(r.get("no_volume", False)))
        against = r["value"][r["sign"] == -direction]
        if np.any(np.isfinite(against)):
            self.other_way = max(self.other_way, float(np.nanmax(against)))

    def note_reach(self, pair: tuple[str, str], reachable: list[Screened], direction: float,
                   where: dict[str, float]) -> None:
        """A pair's designs with a value at the target: the largest kept (``where``: where
        it was read, ``best_reachable``'s keys)."""
        if not reachable:
            return
        top = max(reachable, key=lambda e: e.value)
        if not self.best_reach or top.value > abs(self.best_reach["largest_value"]):  # type: ignore
            # signed: the way the target asks (the search matched magnitudes)
            self.best_design = top.design
            self.best_reach = {"largest_value": direction * top.value,
                               "design": top.design.as_dict(), "pair": "/".join(pair),
                               **where}


def unanswered_error(model: object, target: DesignTarget, seen: SearchSeen,
                     found: bool) -> InputError | None:
    """Where the model gave no force (a force target) for any design inside the bounds and
    nothing was ``found``: refused naming ``kind``, not "unreachable: widen the bounds"
    (a pump's target's: ``pump_targets.no_volume_error``, by the caller)."""
    if seen.no_force and not seen.best_reach and not found:
        return InputError("kind", f"the model {getattr(model, 'name', '')!r} gives no "
                          "blocked-tip force for the designs inside the bounds",
                          "angle_at_pressure or pressure_budget with this model, or "
                          "force_at_pressure with a model fitted with force curves (the "
                          "emulator)")
    return None


def no_design_explanation(model: object, target: DesignTarget, seen: SearchSeen,
                          ranges: dict[str, tuple[float, float]], level: float,
                          direction: float, cancel: threading.Event | None = None) -> str:
    """Why no design inside ``ranges`` meets ``target`` (bending ``direction``), and what
    to change: see the module docstring."""
    what, unit = quantity(target)
    best_reach, best_design = seen.best_reach, seen.best_design
    reach = (abs(best_reach["largest_value"])  # type: ignore[arg-type]
             if best_reach else None)
    if not target.budget and reach is not None and reach >= abs(target.value):
        knob = solve_variable(ranges)
        explanation = (
            f"no design inside the bounds was solved to the target {what} "
            f"{direction * target.value:g} {unit} {target.at_text()} within 1 %, "
            f"although designs there reach {direction * reach:.3g} {unit}: "
            + (f"the value does not cross the target along {knob} within its bounds"
               if knob else "every variable is pinned")
            + "; widen the bounds of the chamber length or the membrane thickness")
    elif reach is None and not target.budget and (
            lower := past_range_explanation(model, seen.past_range, target, level,
                                            direction, seen.past_needed, cancel)) is not None:
        # no design has a number at the target pressure, and some have one below it:
        # their FE range ends below it (bent past the range's end, or past the force's
        # range), so "raise the pressure" would be the wrong way
        explanation = lower
    elif what == "angle" and reach is not None and best_design is not None and (
            end := fe_angle_end(model, best_design, target, level)
            ) is not None and target.value > end and (
            reach >= end - 1.0 or target.value > DATABASE_ANGLE_STOP_DEG):
        # the best design reaches the end of the FE's range, or the target lies past
        # the angle every database curve is solved to: past it no design's angle is
        # known, so neither wider bounds nor more pressure gives a number there (120
        # deg at 1000 Pa, the designs reaching 11.6 deg, said "widen the bounds ... or
        # raise the pressure")
        reaching = ("designs inside the bounds that reach it (up to "
                    if reach >= end - 1.0 else
                    "design inside the bounds that reaches the most (it reaches ")
        explanation = (f"the target angle {direction * target.value:g} deg lies past "
                       f"the FE's range, which ends at {direction * end:.4g} deg for the "
                       f"{reaching}{direction * reach:.3g} deg {target.at_text()}): no "
                       f"angle past it is known; ask for at most {end:.4g} deg in size "
                       "(angle_deg)")
    elif what == "angle" and not reach and target.value > DATABASE_ANGLE_STOP_DEG:
        # no design has a number at the budget's end (each past its FE range there)
        # and no FE curve gets past the angle: 179 deg within 20 kPa said "widen the
        # bounds ... or raise the pressure", at the pressure stop
        explanation = (f"the target angle {direction * target.value:g} deg lies past "
                       f"the FE's range, which ends at "
                       f"{direction * DATABASE_ANGLE_STOP_DEG:g} deg for every design: "
                       f"no angle past it is known; ask for at most "
                       f"{DATABASE_ANGLE_STOP_DEG:g} deg in size (angle_deg)")
    else:
        # a force target: more pressure helps only as far as the best design's force
        # is given (its blocked-tip FE curve ends at a pressure maximum, or its free
        # range ends)
        end = (force_past_target(model, best_design, target.pressure_pa, level)
               if what == "force" and best_design is not None else None)
        widen = ("widen the bounds (longer chamber, thinner membrane, softer membrane)"
                 if solve_variable(ranges) is not None else
                 "every variable is pinned to one design: free a bound (L, t, T, b, h "
                 "or a stiffness scale)")
        if end is None or end[1] >= target.value:
            widen += " or " + MORE_LESS[target.at_field][0]
        else:
            widen += (f"; for the design that reaches the most at "
                      f"{target.pressure_pa:g} Pa raising the pressure does not get "
                      f"there: its force is given only to {end[0]:.0f} Pa, up to "
                      f"{direction * end[1]:.3g} {unit} (past it the FE's blocked-tip "
                      "or free curve ends: /v1/predict says which)")
        explanation = (f"the target {what} {direction * target.value:g} {unit} "
                       f"{target.at_text()} is not reachable by any design "
                       f"bending {WAY[direction]} inside the bounds"
                       + (f"; the largest reachable {target.at_text(exact=True)} is "
                          f"{direction * reach:.3g} {unit}" if reach else "")
                       + f": {widen}")
    if seen.other_way >= target.value:
        # only where the other way reaches the target's size: a hint that it cannot
        # meet either ("reach -5.22 deg: ask for -80 deg") was no help
        explanation += (f"; designs bending {WAY[-direction]} reach "
                        f"{-direction * seen.other_way:.3g} {unit} there: ask for "
                        f"{-direction * target.value:g} {unit} to search them")
    return explanation


def passed_over_note(n_listed: int, n_results: int, near_copies: int,
                     not_as_screened: int) -> str:
    """Why fewer designs are listed than asked for although more meet the target: the
    others are near-copies of a listed design (closer than MIN_SPACING in the bounds' unit
    cube, the same pair) or did not meet the target within 1 % when asked back."""
    if n_listed >= n_results or not (near_copies or not_as_screened):
        return ""
    why = []
    if near_copies:
        why.append(f"{near_copies} {'is a near-copy' if near_copies == 1 else 'are near-copies'}"
                   f" of a listed design, within {MIN_SPACING:g} of the bounds' span")
    if not_as_screened:
        why.append(f"{not_as_screened} missed the target by more than 1 % when asked back")
    return f"; {n_results} were asked for: of the others, {' and '.join(why)}"


def stretch_hazard_note(candidates: list[DesignCandidate]) -> str:
    """The explanation's words on the listed designs whose curve to the target carries
    ``high_membrane_stretch`` (surrogate/emulator/stretch_hazard.py): they reach it where
    their emulated membrane stretch has passed the hazard stretch, past which many FE
    curves end in a Newton failure. The ranking is unchanged (a flag, not a cut); ""
    when none does."""
    ranks = [str(c.rank) for c in candidates
             if STRETCH_FLAG in (c.curve.validity or {}).get("flags", ())]
    if not ranks:
        return ""
    return (f"; rank{'s' if len(ranks) > 1 else ''} {', '.join(ranks)} reach"
            f"{'' if len(ranks) > 1 else 'es'} it past where the emulated membrane stretch "
            f"passes {HAZARD_STRETCH:g} (flag {STRETCH_FLAG}), past which many FE curves end "
            "in a Newton failure: an FE solve (POST /v1/solve) tells whether the design's "
            "curve gets there")


def fe_angle_end(model: object, design: Design, target: DesignTarget, level: float
                 ) -> float | None:
    """|angle| (deg) at which ``design``'s FE range ends, as the model's answer where
    ``target`` is met states it (``validity["fe_limit_angle_deg"]``: the emulator's, 90
    deg at the FE's angle stop); None where the model states none."""
    try:
        end = ask(model, design, target, [target.at], level).validity.get(
            "fe_limit_angle_deg")
    except InputError:
        return None
    return abs(float(end)) if end is not None and np.isfinite(end) else None


def force_past_target(model: object, design: Design, pressure_pa: float, level: float
                      ) -> tuple[float, float] | None:
    """The highest pressure (Pa) up to 2x ``pressure_pa`` at which ``design``'s force is
    still given, and the largest |force| (mN) up to it, where the force ends before 2x
    (the design's blocked-tip FE curve ends at a pressure maximum, or its free range
    does); None where it goes on (more pressure gives more force) or is never given."""
    p = pressure_pa * np.array(HIGHER_PRESSURE_FACTORS)
    try:
        pred = model.predict(design, p, level=level)  # type: ignore[attr-defined]
    except InputError:
        return None
    if pred.force_mn is None:
        return None
    force = np.abs(np.asarray(pred.force_mn, float))
    given = np.isfinite(force)
    if not given.any() or given[-1]:
        return None
    last = int(np.flatnonzero(given)[-1])
    return float(p[last]), float(np.max(force[:last + 1]))


def past_range_explanation(model: object, past_range: list[list[Design]],
                           target: DesignTarget, level: float, direction: float,
                           needed_pa: list[float] | None = None,
                           cancel: threading.Event | None = None) -> str | None:
    """Why no design inside the bounds answers an exact target where each one is past its
    FE range at the target pressure (a soft design that bends past the FE curve's end
    before it, a force asked past the blocked-tip curves' range), with what is possible:
    the highest of LOWER_PRESSURE_FRACTIONS x the target pressure (Pa; a pump's target:
    volume or time) at which designs of ``past_range`` (each pair's candidates with no
    number there) are answered, and the largest |value| there, and the pressures (Pa;
    volumes, ul) at which they reach the target angle (``needed_pa``); None when no design
    is answered at any of them (no FE range to name).
    Until 2026-12-06 this said "not reachable ...: widen the bounds (longer chamber,
    thinner membrane, softer membrane) or raise the pressure" -- the wrong way."""
    what, unit = quantity(target)
    where = target.at_text()
    text = (f"the target {what} {direction * target.value:g} {unit} {where} has no answer: "
            f"every design bending {WAY[direction]} inside the bounds is past its FE range "
            f"{where} (no number the FE supports there)")
    for fraction in LOWER_PRESSURE_FRACTIONS:
        lower = target.with_at(fraction * target.at)
        largest = 0.0
        for designs in past_range:
            stop_if_cancelled(cancel)
            r = screen(model, designs, lower, level)
            keep_direction(r, direction)
            if np.any(np.isfinite(r["value"])):
                largest = max(largest, float(np.nanmax(r["value"])))
        if largest > 0:
            axis = "ul" if target.by_volume else "Pa"
            reached = (f" (they reach {direction * target.value:g} deg at "
                       f"{min(needed_pa):.4g}-{max(needed_pa):.4g} {axis})" if needed_pa
                       else "")
            return (text + f"; {lower.at_text()} designs there reach up to "
                    f"{direction * largest:.3g} {unit}{reached}: "
                    f"{MORE_LESS[target.at_field][1]}"
                    + ("" if target.kind == "force_at_pressure" else
                       f", or ask for a {BUDGET_OF[target.kind]} target"))
    return None
