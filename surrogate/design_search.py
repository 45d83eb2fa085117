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
angle_at_time, time_budget: surrogate/pump_targets.py) by the model's answers by injected
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
from dataclasses import dataclass, replace

import numpy as np

from solver.design import Design
from solver.design_space import (
    BOX_MM,
    BOX_WIDTH_MM,
    GEOMETRY,
    PAIRS,
    STIFFNESS_SCALE_RANGE,
    scaled_material,
)
from solver.errors import InputError
from solver.settings import SolverSettings
from surrogate.band_level import z_value
from surrogate.emulator.stretch_hazard import FLAG as STRETCH_FLAG
from surrogate.emulator.stretch_hazard import HAZARD_STRETCH
from surrogate.errors import stop_if_cancelled
from surrogate.exponential.inverse_design import (
    DesignCandidate,
    DesignTarget,
    InverseDesignResult,
    resolve_objective,
)
from surrogate.pump_targets import (
    ask,
    no_volume_error,
    require_volumes,
    screen_by_volume,
    volume_report,
)

CANDIDATES_PER_PAIR = 512
#: designs returned at most (the HTTP schema and the CLI read it)
N_RESULTS_MAX = 20
#: candidates per pair, nearest the target, solved exactly to it: 6 per result of the
#: largest answer, whatever n_results is (30 found a best design of score 0.0107 where
#: 120 found 0.0085, for 30 deg at 1500 Pa over the box: 1.4 -> 3.1 s on one thread)
SOLVED_PER_PAIR = 6 * N_RESULTS_MAX
MIN_SPACING = 0.08
CURVE_POINTS = 41
# Bisection steps in L: the bracket shrinks to (L_hi / L_lo)^(2^-16), 2.3e-5 of L over the
# whole box (the angle moves about as L does), far inside the 1 % the hit is held to.
BISECTION_STEPS = 16


@dataclass(frozen=True)
class SearchBounds:
    """(low, high) per geometry field (mm) and per layer's stiffness scale; None = the
    box for geometry, (1, 1) for the scales. ``pairs``: allowed (body, membrane) ids."""

    L_mm: tuple[float, float] | None = None
    t_mm: tuple[float, float] | None = None
    T_mm: tuple[float, float] | None = None
    b_mm: tuple[float, float] | None = None
    h_mm: tuple[float, float] | None = None
    body_stiffness_scale: tuple[float, float] | None = None
    membrane_stiffness_scale: tuple[float, float] | None = None
    pairs: tuple[tuple[str, str], ...] | None = None

    def ranges(self) -> dict[str, tuple[float, float]]:
        """Validated ranges of every searched variable, clipped to the box."""
        out: dict[str, tuple[float, float]] = {}
        for name in GEOMETRY:
            out[name] = self._range(name, getattr(self, name), BOX_MM[name], "mm")
        for name in ("body_stiffness_scale", "membrane_stiffness_scale"):
            out[name] = self._range(name, getattr(self, name), STIFFNESS_SCALE_RANGE, "",
                                    default=(1.0, 1.0))
        return out

    @staticmethod
    def _range(name: str, value: tuple[float, float] | None, box: tuple[float, float],
               unit: str, default: tuple[float, float] | None = None
               ) -> tuple[float, float]:
        if value is None:
            return default or box
        lo, hi = (float(v) for v in value)
        if not (np.isfinite(lo) and np.isfinite(hi)) or not 0 < lo <= hi:
            # lengths and stiffness scales are positive: [-1, 5] is no bound to clip
            raise InputError(name, f"bounds {list(value)!r}",
                             "[low, high] with 0 < low <= high")
        if hi < box[0] or lo > box[1]:
            raise InputError(name, f"bounds {list(value)!r} lie outside the box",
                             f"within {box[0]:g}..{box[1]:g} {unit}".rstrip())
        return max(lo, box[0]), min(hi, box[1])

    def clipped(self, ranges: dict[str, tuple[float, float]]) -> list[str]:
        """What ``ranges`` (``ranges()``) searched where the bounds given reach past the
        box: "L_mm 4-18 (of 2-30 given)" -- said with the answer, so that "no design meets
        the target" is not read as covering what was never searched."""
        out = []
        for name, (lo, hi) in ranges.items():
            given = getattr(self, name)
            if given is not None and (float(given[0]), float(given[1])) != (lo, hi):
                out.append(f"{name} {lo:g}-{hi:g} (of {float(given[0]):g}-"
                           f"{float(given[1]):g} given)")
        return out

    def allowed_pairs(self) -> tuple[tuple[str, str], ...]:
        if self.pairs is None:
            return PAIRS
        for pair in self.pairs:
            if tuple(pair) not in PAIRS:
                scaled = (" (a layer's stiffness scale is searched within its bounds: "
                          "body_stiffness_scale_bounds, membrane_stiffness_scale_bounds)"
                          if "*" in pair[0] + pair[1] else "")
                raise InputError("material_pairs", f"pair {pair[0]}/{pair[1]} is not in the "
                                 f"box{scaled}", ", ".join(f"{b}/{m}" for b, m in PAIRS))
        # each pair once, in the order given: a repeated pair would be searched again
        return tuple(dict.fromkeys(tuple(p) for p in self.pairs))  # type: ignore[misc]


VARIABLES = (*GEOMETRY, "body_stiffness_scale", "membrane_stiffness_scale")


def _design(pair: tuple[str, str], values: dict[str, float]) -> Design:
    return Design(body_material=scaled_material(pair[0], values["body_stiffness_scale"]),
                  membrane_material=scaled_material(pair[1],
                                                    values["membrane_stiffness_scale"]),
                  W_mm=BOX_WIDTH_MM, **{n: values[n] for n in GEOMETRY}).validated()


def _candidates(ranges: dict[str, tuple[float, float]], slices: list[dict] | None,
                seed: int, count: int = CANDIDATES_PER_PAIR) -> list[dict[str, float]]:
    from scipy.stats import qmc

    u = qmc.Sobol(d=len(VARIABLES), scramble=True, seed=seed).random(count)
    out = []
    for row in u:
        values = {}
        for x, name in zip(row, VARIABLES):
            lo, hi = ranges[name]
            values[name] = float(lo * (hi / lo) ** x) if hi > lo else lo
        out.append(values)
    if slices is None:
        return out
    pinned = []
    for sl in slices:  # a model that covers slices: pin T, b, h (and the scales to 1)
        if not all(ranges[n][0] - 1e-9 <= sl[n] <= ranges[n][1] + 1e-9
                   for n in ("T_mm", "b_mm", "h_mm")):
            continue
        for v in out[: max(count // max(len(slices), 1), 16)]:
            pinned.append({**v, "T_mm": sl["T_mm"], "b_mm": sl["b_mm"], "h_mm": sl["h_mm"],
                           "body_stiffness_scale": 1.0, "membrane_stiffness_scale": 1.0})
    return pinned


@dataclass
class _Eval:
    pair: tuple[str, str]
    values: dict[str, float]
    design: Design
    needed: float = np.nan       # pressure (Pa; a pump's target: volume, ul) for the angle
    needed_lo: float = np.nan
    needed_hi: float = np.nan
    value: float = np.nan        # |angle| (deg) or |force| (mN) at the target pressure
                                 # (a pump's target: |angle| at the target volume)
    value_lo: float = np.nan
    value_hi: float = np.nan


_WAY = {1.0: "away from the membrane (positive angles)",
        -1.0: "towards the membrane (negative angles)"}


def _direction(target: DesignTarget) -> float:
    """+1: the target bends away from the membrane; -1: towards it."""
    raw = target.force_mn if target.kind == "force_at_pressure" else target.angle_deg
    return -1.0 if float(raw) < 0 else 1.0  # type: ignore[arg-type]


def _screen(model: object, designs: list[Design], target: DesignTarget, level: float,
            band: bool = True) -> dict[str, np.ndarray]:
    """|value| at the target pressure with its band, the pressure needed for the
    target angle with its band, and the design's bending direction (``sign``, +1 / -1,
    0 unknown), for every design (NaN where the model has no answer). Uses the model's
    batch ``evaluate_designs`` when it has one (the emulator), else its ``predict`` and
    ``inverse`` per design. ``band=False``: a pump's target's bands may be NaN (the
    emulator's batch then reads the means alone: a bisection step's)."""
    if target.by_volume:
        return screen_by_volume(model, designs, target, level, band)
    angle = None if target.kind == "force_at_pressure" else target.value
    batch = getattr(model, "evaluate_designs", None)
    if batch is not None:
        out = batch(designs, target.pressure_pa, angle, level)
        if target.kind == "force_at_pressure":
            out = {**out, "angle": np.abs(out["force"]), "angle_lo": np.abs(out["force_lo"]),
                   "angle_hi": np.abs(out["force_hi"])}
        lo = np.fmin(out["angle_lo"], out["angle_hi"])
        hi = np.fmax(out["angle_lo"], out["angle_hi"])
        return {"value": np.abs(out["angle"]), "value_lo": lo, "value_hi": hi,
                "needed": out["needed"], "needed_lo": out["needed_lo"],
                "needed_hi": out["needed_hi"], "sign": out["sign"]}
    keys = ("value", "value_lo", "value_hi", "needed", "needed_lo", "needed_hi", "sign")
    res = {k: np.full(len(designs), np.nan) for k in keys}
    res["no_force"] = np.zeros(len(designs), bool)
    for i, design in enumerate(designs):
        try:
            pred = model.predict(design, [target.pressure_pa], level=level)  # type: ignore
        except InputError:
            continue
        if target.kind == "force_at_pressure":
            if pred.force_mn is None:       # the model has no force for this design
                res["no_force"][i] = True
                continue
            vals = np.abs([pred.force_mn[0], pred.force_lower_mn[0], pred.force_upper_mn[0]])
            res["sign"][i] = np.sign(pred.force_mn[0]) if np.isfinite(pred.force_mn[0]) else 0
        else:
            vals = np.abs([pred.angle_deg[0], pred.lower_deg[0], pred.upper_deg[0]])
            sign = _bending_sign(model, design, pred, target.pressure_pa, level)
            res["sign"][i] = sign
            try:
                inv = model.inverse(design, [(sign or 1.0) * target.value],  # type: ignore
                                    level=level)
                res["needed"][i] = inv.pressure_pa[0]
                res["needed_lo"][i], res["needed_hi"][i] = inv.lower_pa[0], inv.upper_pa[0]
            except InputError:
                pass
        finite = vals[np.isfinite(vals)]  # none past the FE's range: no band (nanmin warns)
        res["value"][i], res["value_lo"][i], res["value_hi"][i] = (
            vals[0], *((finite.min(), finite.max()) if finite.size else (np.nan, np.nan)))
    return res


def _bending_sign(model: object, design: Design, pred: object, pressure_pa: float,
                  level: float) -> float:
    """+1 / -1: which way ``design`` bends (``pred``: its prediction at ``pressure_pa``;
    where that is past the FE's range, the first answered of a few lower pressures), 0
    when no pressure is answered."""
    angle = float(pred.angle_deg[0])  # type: ignore[attr-defined]
    if np.isfinite(angle) and angle != 0:
        return float(np.sign(angle))
    low = model.predict(design, pressure_pa * np.array([0.5, 0.25, 0.125]),  # type: ignore
                        level=level).angle_deg
    found = [a for a in low if np.isfinite(a) and a != 0]
    return float(np.sign(found[0])) if found else 0.0


def _keep_direction(r: dict[str, np.ndarray], direction: float) -> np.ndarray:
    """In place: no answer (NaN) for the designs of ``r`` (``_screen``) that bend against
    ``direction``; returns which those were."""
    wrong = r["sign"] == -direction
    for k in ("value", "value_lo", "value_hi", "needed", "needed_lo", "needed_hi"):
        r[k] = np.where(wrong, np.nan, r[k])
    return wrong


# The variables an exact target is solved along, in order of preference: the first whose
# bounds are not pinned. The chamber length moves the angle most directly; a lab with a
# fixed mould length still varies the membrane (thickness, then its stiffness).
KNOBS = ("L_mm", "t_mm", "membrane_stiffness_scale", "h_mm", "b_mm", "T_mm",
         "body_stiffness_scale")


def solve_variable(ranges: dict[str, tuple[float, float]]) -> str | None:
    """The variable an exact target is solved along (KNOBS), None when all are pinned."""
    return next((n for n in KNOBS if ranges[n][1] > ranges[n][0]), None)


def _solve_along(model: object, evals: list[_Eval], target: DesignTarget, level: float,
                 name: str, bounds: tuple[float, float],
                 cancel: threading.Event | None = None) -> list[_Eval]:
    """Bisection along the variable ``name`` within ``bounds`` (all candidates at once,
    geometric) so that the value at the target pressure equals the target; a value past
    the FE's range counts as too large, a design bending the other way as too small (an
    Ecoflex/Ecoflex membrane thick enough to pass the stiffness balance: without it both
    ends of t counted as "too large" and a reachable target was called infeasible).
    Either direction: a candidate is solved when the value minus the target changes sign
    between the bounds."""
    if not evals:
        return []
    lo = np.full(len(evals), bounds[0])
    hi = np.full(len(evals), bounds[1])

    def f(x: np.ndarray, band: bool = False) -> tuple[np.ndarray, list[Design], dict]:
        designs = [_design(e.pair, {**e.values, name: float(v)}) for e, v in zip(evals, x)]
        r = _screen(model, designs, target, level, band)
        other_way = _keep_direction(r, _direction(target))     # no hit there
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
    out = []
    for i, e in enumerate(evals):
        if ok[i] and np.isfinite(f_mid[i]) and abs(f_mid[i]) <= 0.01 * target.value:
            out.append(_Eval(e.pair, {**e.values, name: float(mid[i])}, designs[i],
                             *(float(r[k][i]) for k in ("needed", "needed_lo", "needed_hi",
                                                         "value", "value_lo", "value_hi"))))
    return out


def _answers_as_screened(model: object, e: _Eval, target: DesignTarget, level: float
                         ) -> bool:
    """A candidate asked as a user asks it (``predict``, at the target pressure or, for
    a budget, at the pressure it needs; ``predict_volume`` at the volume for a pump's
    target): within 1 % of the target. The batch screen and
    ``predict`` take different paths near the stiffness balance (the balance model's
    answer is predict's only): a candidate listed at 60 deg read 62.8 when predicted back
    (an audit of the thirty-fifth session)."""
    budget = target.budget
    at = e.needed if budget else target.at
    if budget and not np.isfinite(at):
        return True
    try:
        p = ask(model, e.design, target, [at], level)
    except InputError:
        return False
    got = (p.force_mn[0] if target.kind == "force_at_pressure" and p.force_mn is not None
           else np.nan if target.kind == "force_at_pressure" else p.angle_deg[0])
    if budget and not np.isfinite(got):     # the angle meets the budget at the FE's end
        return True
    return bool(np.isfinite(got) and abs(abs(got) - target.value) <= 0.01 * target.value)


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


# the angle every database curve is solved to (the default solve's angle stop): no
# model fitted from them knows an angle past it
DATABASE_ANGLE_STOP_DEG = SolverSettings().max_angle_deg

TOLERANCE_MM = 0.01


def _tolerance(model: object, design: Design, target: DesignTarget, at: float,
               level: float) -> dict[str, float] | None:
    """The value at ``at`` (the pressure, Pa, or for a pump's target the injected
    volume, ul; signed angle, deg, or force, mN) changed by making
    each length TOLERANCE_MM larger, the others kept (central differences; one-sided at
    the box's faces): what a mould's tolerance does to the answer. A candidate at 45.0 deg
    read 46.4 with its t rounded to 0.01 mm, 5x its band (an audit of the thirty-fifth
    session). None where the model has no number there."""
    def value(d: Design) -> float:
        try:
            p = ask(model, d, target, [at], level)
        except InputError:
            return float("nan")
        if target.kind == "force_at_pressure":
            return float(p.force_mn[0]) if p.force_mn is not None else float("nan")
        return float(p.angle_deg[0])

    here = value(design)            # asked once: only a one-sided difference needs it
    out = {}
    for name in ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm"):
        x = getattr(design, name)
        # the body length and chamber position by the solver's rule, as the search's own
        up, down = (value(replace(design, body_length_mm=None, chamber_offset_mm=None,
                                  **{name: x + s * TOLERANCE_MM}).validated())
                    for s in (1, -1))
        slope = ((up - down) / 2 if np.isfinite(up) and np.isfinite(down) else
                 up - here if np.isfinite(up) else here - down)
        if not np.isfinite(slope):
            return None
        out[name] = float(slope)
    return out


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


#: pressures tried above the target's, as multiples of it (force_past_target)
HIGHER_PRESSURE_FACTORS = tuple(np.round(np.linspace(1.0, 2.0, 41), 3))


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


#: fractions of the target pressure tried, highest first, for the highest pressure at which
#: designs inside the bounds are still within their FE range (past_range_explanation)
LOWER_PRESSURE_FRACTIONS = (0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1, 0.05)


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
    what, unit = (("force", "mN") if target.kind == "force_at_pressure" else ("angle", "deg"))
    where = target.at_text()
    text = (f"the target {what} {direction * target.value:g} {unit} {where} has no answer: "
            f"every design bending {_WAY[direction]} inside the bounds is past its FE range "
            f"{where} (no number the FE supports there)")
    for fraction in LOWER_PRESSURE_FRACTIONS:
        lower = target.with_at(fraction * target.at)
        largest = 0.0
        for designs in past_range:
            stop_if_cancelled(cancel)
            r = _screen(model, designs, lower, level)
            _keep_direction(r, direction)
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


#: the budget target of each exact angle target (past_range_explanation)
BUDGET_OF = {"angle_at_pressure": "pressure_budget", "angle_at_volume": "volume_budget",
             "angle_at_time": "time_budget"}


# what a candidate's score is, per objective (lower ranks first)
SCORE_MEANING = {
    "certainty": "the band's width over the value at the target pressure or volume "
                 "(lower: surer)",
    "pressure": "the pressure needed for the target, Pa",
    "volume": "the injected volume needed for the target, ul (time = volume / flow)",
    "margin": "the band's upper end of the pressure needed, Pa (a pump's budget: of the "
              "volume needed, ul)",
    "compact": "the chamber length L, mm",
}


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


#: how to ask for more and for less of a target's axis (the explanations of a target out
#: of reach, and of one past every design's FE range)
MORE_LESS = {"pressure_pa": ("raise the pressure", "lower the pressure (pressure_pa)"),
             "volume_ul": ("inject more (volume_ul)", "inject less (volume_ul)"),
             "time_s": ("pump for longer (time_s)", "pump for less time (time_s)")}


def _where(target: DesignTarget) -> dict[str, float]:
    """Where ``best_reachable`` was read: at the target pressure (Pa), or at the pump's
    volume (ul) and time (s)."""
    if not target.by_volume:
        return {"at_pressure_pa": float(target.at)}
    out = {"at_volume_ul": float(target.at)}
    if target.time_s is not None:
        out["at_time_s"] = float(target.time_s)
    return out


def _score(e: _Eval, objective: str, target: DesignTarget) -> float:
    if objective in ("pressure", "volume"):      # what the budget is in
        return e.needed
    if objective == "margin":
        return e.needed_hi
    if objective == "compact":
        return e.values["L_mm"]
    width = e.value_hi - e.value_lo
    return width / max(e.value, 1e-9)


def _unit(e: _Eval, ranges: dict[str, tuple[float, float]]) -> np.ndarray:
    out = []
    for name in VARIABLES:
        lo, hi = ranges[name]
        out.append(0.0 if hi <= lo else np.log(e.values[name] / lo) / np.log(hi / lo))
    return np.array(out)


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
    direction = _direction(target)
    n_evaluated = 0
    past_range: list[list[Design]] = []   # per pair: those with no number (see below)
    past_needed: list[float] = []           # the pressures they need for the angle, Pa
    feasible: list[_Eval] = []
    best_reach: dict[str, object] = {}
    best_design: Design | None = None   # the design of best_reach
    other_way = 0.0          # the largest |value| of designs bending against the target
    no_force = 0             # designs the model answers with no force (force targets)
    no_volume = 0            # designs the model answers with no volume (a pump's targets)
    for pair in bounds.allowed_pairs():
        stop_if_cancelled(cancel)
        slices = slices_fn(pair) if slices_fn is not None else None
        if slices is not None and not slices:
            continue
        designs, kept = [], []
        count = (CANDIDATES_PER_PAIR if hasattr(model, "evaluate_designs")
                 else CANDIDATES_PER_PAIR // 4)   # one predict per design: fewer
        for values in _candidates(ranges, slices, seed, count):
            try:
                designs.append(_design(pair, values))
                kept.append(values)
            except InputError:
                continue
        if not designs:
            continue
        r = _screen(model, designs, target, level)
        n_evaluated += len(designs)
        # the designs bending the way asked with no number at the target pressure
        is_past = (r["sign"] == direction) & ~np.isfinite(r["value"])
        if np.any(is_past):
            past_range.append([d for d, past in zip(designs, is_past, strict=True) if past])
            past_needed += [float(v) for v in r["needed"][is_past] if np.isfinite(v)]
        no_force += int(np.sum(r.get("no_force", False)))
        no_volume += int(np.sum(r.get("no_volume", False)))
        against = r["value"][r["sign"] == -direction]
        if np.any(np.isfinite(against)):
            other_way = max(other_way, float(np.nanmax(against)))
        _keep_direction(r, direction)
        evals = [_Eval(pair, v, d, *(float(r[k][i]) for k in (
                     "needed", "needed_lo", "needed_hi", "value", "value_lo", "value_hi")))
                 for i, (v, d) in enumerate(zip(kept, designs)) if np.isfinite(r["value"][i])
                 or np.isfinite(r["needed"][i])]
        if not evals:
            continue
        reachable = [e for e in evals if np.isfinite(e.value)]
        if reachable:
            top = max(reachable, key=lambda e: e.value)
            if not best_reach or top.value > abs(best_reach["largest_value"]):  # type: ignore
                # signed: the way the target asks (the search matched magnitudes)
                best_design = top.design
                best_reach = {"largest_value": direction * top.value,
                              "design": top.design.as_dict(), "pair": "/".join(pair),
                              **_where(target)}
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
        hits = _solve_along(model, solved, target, level, knob, ranges[knob], cancel)
        n_evaluated += (BISECTION_STEPS + 3) * len(solved)
        feasible += hits
    if no_force and not best_reach and not feasible:
        # not "unreachable: widen the bounds": the model has no force to search with
        raise InputError("kind", f"the model {getattr(model, 'name', '')!r} gives no "
                         "blocked-tip force for the designs inside the bounds",
                         "angle_at_pressure or pressure_budget with this model, or "
                         "force_at_pressure with a model fitted with force curves (the "
                         "emulator)")
    if no_volume and not best_reach and not feasible:
        raise no_volume_error(model, target)
    feasible = [e for e in feasible if np.isfinite(_score(e, objective, target))]
    feasible.sort(key=lambda e: _score(e, objective, target))
    chosen: list[_Eval] = []
    near_copies = not_as_screened = 0   # the feasible designs passed over, and why
    for e in feasible:
        stop_if_cancelled(cancel)
        u = _unit(e, ranges)
        if any(e.pair == c.pair and np.linalg.norm(u - _unit(c, ranges)) < MIN_SPACING
               for c in chosen):
            near_copies += 1
        elif _answers_as_screened(model, e, target, level):
            chosen.append(e)
        else:
            not_as_screened += 1
        if len(chosen) == n_results:
            break
    candidates = []
    for rank, e in enumerate(chosen, 1):
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
        candidates.append(DesignCandidate(
            rank=rank, design=e.design, family="/".join(e.pair),
            score=float(_score(e, objective, target)), pressure_needed_pa=needed[0],
            pressure_lower_pa=needed[1], pressure_upper_pa=needed[2],
            value_at_pressure=direction * value, value_lower=lo, value_upper=hi,
            curve=curve, change_per_0_01_mm=_tolerance(model, e.design, target, at_where,
                                                       level), **pump))
    if candidates:
        explanation = (f"{len(feasible)} of {n_evaluated} evaluated designs meet the target; "
                       f"the {len(candidates)} best by {objective} are listed"
                       + passed_over_note(len(candidates), n_results, near_copies,
                                          not_as_screened)
                       + stretch_hazard_note(candidates))
    else:
        what = "force" if target.kind == "force_at_pressure" else "angle"
        unit = "mN" if target.kind == "force_at_pressure" else "deg"
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
                lower := past_range_explanation(model, past_range, target, level,
                                                direction, past_needed, cancel)) is not None:
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
                           f"bending {_WAY[direction]} inside the bounds"
                           + (f"; the largest reachable {target.at_text(exact=True)} is "
                              f"{direction * reach:.3g} {unit}" if reach else "")
                           + f": {widen}")
        if other_way >= target.value:
            # only where the other way reaches the target's size: a hint that it cannot
            # meet either ("reach -5.22 deg: ask for -80 deg") was no help
            explanation += (f"; designs bending {_WAY[-direction]} reach "
                            f"{-direction * other_way:.3g} {unit} there: ask for "
                            f"{-direction * target.value:g} {unit} to search them")
    clipped = bounds.clipped(ranges)
    if clipped:
        explanation += ("; searched within the emulator's box: " + ", ".join(clipped))
    return InverseDesignResult(target=target, objective=objective,
                               feasible=bool(candidates), candidates=tuple(candidates),
                               explanation=explanation, best_reachable=best_reach,
                               n_evaluated=n_evaluated)
