"""Inverse design: which (material pair, L, t) meets a target, ranked by an objective.

Targets (``DesignTarget.kind``):

    angle_at_pressure   reach |angle_deg| exactly at pressure_pa. For each t the chamber
                        length is closed form, L = |angle| / (|a| (exp(x + c x^2) - 1)),
                        x = p / tau(t); candidates are the (L, t) with L inside the bounds.
    pressure_budget     reach |angle_deg| at a pressure of at most pressure_pa; needed
                        pressure p = tau x, x + c x^2 = ln(1 + |angle| / |A|), on an L x t grid.
    force_at_pressure   as angle_at_pressure with the family's force model (mN).

A syringe pump's targets (volume_ul injected, or time_s at flow_ul_s from the undeformed
state: volume = flow x time) are searched over the box by ``surrogate.design_search``
only; this family grid refuses them:

    angle_at_volume     reach |angle_deg| exactly at the injected volume_ul
    volume_budget       reach |angle_deg| with no more than volume_ul injected
    angle_at_time       reach |angle_deg| exactly after time_s at flow_ul_s
    time_budget         reach |angle_deg| within time_s at flow_ul_s

Angles are matched in magnitude: a reversed material pair (a < 0) is a candidate too,
and its predictions carry the negative sign. Objectives (lower score ranks first):

    pressure    pressure needed (pressure_budget)
    volume      injected volume needed (volume_budget, time_budget: time = volume / flow)
    margin      band upper end of the pressure (or volume) needed, i.e. the largest
                margin to the budget at the band's pessimistic end (the budgets)
    compact     chamber length L
    certainty   relative width of the prediction band at the target pressure

Evaluation is vectorised over a grid (per family), the best cell is refined on a finer
local grid, and the ranked list keeps designs at least ``MIN_SPACING`` apart (normalised
L, t). Bounds default to each family's fitted domain, with t >= 0.5 mm (no two-balloon
designs unless the bounds ask for them).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from solver.design import Design
from solver.errors import InputError
from surrogate.band_level import z_value
from surrogate.exponential import bands, equations
from surrogate.exponential.family import Family
from surrogate.exponential.paper_tables import TWO_BALLOON_BELOW_t_MM
from surrogate.exponential.parameters import ModelParameters
from surrogate.exponential.surrogate import Surrogate
from surrogate.predictor import FE_VOLUME_STOP_UL, SMALLEST_NORMAL, Prediction
from surrogate.volume_control import FLOW_RANGE, MAX_FLOW_UL_S, MAX_TIME_S, MIN_FLOW_UL_S

KINDS = ("angle_at_pressure", "pressure_budget", "force_at_pressure", "angle_at_volume",
         "volume_budget", "angle_at_time", "time_budget")
#: the syringe pump's targets: by injected volume, or by time at a flow rate
TIME_KINDS = ("angle_at_time", "time_budget")
VOLUME_KINDS = ("angle_at_volume", "volume_budget", *TIME_KINDS)
#: targets met within a budget (the others exactly)
BUDGET_KINDS = ("pressure_budget", "volume_budget", "time_budget")
#: the target a search answers when none is named (HTTP and CLI alike)
DEFAULT_KIND = "angle_at_pressure"
#: the largest target magnitudes taken: |angle| in deg, |force| in mN
MAX_TARGET = {"angle_deg": 360.0, "force_mn": 1e4}
OBJECTIVES = ("pressure", "volume", "margin", "compact", "certainty")
DEFAULT_OBJECTIVE = {"angle_at_pressure": "certainty", "pressure_budget": "pressure",
                     "force_at_pressure": "certainty", "angle_at_volume": "certainty",
                     "volume_budget": "volume", "angle_at_time": "certainty",
                     "time_budget": "volume"}
#: what a listed design reports for a syringe pump's target (DesignCandidate)
PUMP_FIELDS = ("volume_needed_ul", "volume_lower_ul", "volume_upper_ul", "time_needed_s",
               "time_lower_s", "time_upper_s", "angle_at_volume_deg",
               "angle_at_volume_lower_deg", "angle_at_volume_upper_deg",
               "pressure_at_volume_pa")
MIN_SPACING = 0.08
GRID = 48
CURVE_POINTS = 41


def resolve_objective(target: DesignTarget, objective: str | None) -> str:
    """The ranking objective for ``target``: the given one, checked, or the target's
    default (InputError naming ``objective`` and the allowed values otherwise)."""
    objective = objective or DEFAULT_OBJECTIVE[target.kind]
    if objective not in OBJECTIVES:
        raise InputError("objective", f"unknown objective {objective!r}", " | ".join(OBJECTIVES))
    budget_of = {"pressure": ("pressure_budget",), "volume": ("volume_budget", "time_budget"),
                 "margin": BUDGET_KINDS}
    if objective in budget_of and target.kind not in budget_of[objective]:
        ranks = [o for o, kinds in budget_of.items() if target.kind in kinds]
        raise InputError("objective", f"{objective!r} ranks {' or '.join(budget_of[objective])}"
                         " targets only", " | ".join((*ranks, "certainty", "compact")))
    return objective


@dataclass(frozen=True)
class DesignTarget:
    """What the design must do; units in the names. See the module docstring. A pump's
    target gives volume_ul, or time_s with flow_ul_s, and no pressure_pa."""

    kind: str
    pressure_pa: float | None = None
    angle_deg: float | None = None
    force_mn: float | None = None
    volume_ul: float | None = None
    time_s: float | None = None
    flow_ul_s: float | None = None

    def validated(self) -> DesignTarget:
        if self.kind not in KINDS:
            raise InputError("kind", f"unknown target {self.kind!r}", " | ".join(KINDS))
        uses = self._fields()
        for name in ("pressure_pa", "volume_ul", "time_s", "flow_ul_s"):
            if name not in uses and getattr(self, name) is not None:   # never dropped
                raise InputError(name, f"the {self.kind} target does not use {name}",
                                 f"leave {name} out (the {self.kind} target takes "
                                 f"{', '.join(uses)})")
        if self.kind in TIME_KINDS:
            self._check_time()
        elif self.kind in VOLUME_KINDS:
            if not _finite(self.volume_ul) or not (_positive(self.volume_ul)
                                                   and self.volume_ul <= FE_VOLUME_STOP_UL):
                raise InputError("volume_ul", f"the {self.kind} target needs an injected "
                                 "volume within the FE's volume stop, got "
                                 + ("none" if self.volume_ul is None else repr(self.volume_ul)),
                                 f"0 < volume_ul <= {FE_VOLUME_STOP_UL:g} ul")
        elif not _finite(self.pressure_pa) or not (_positive(self.pressure_pa)
                                                         and self.pressure_pa <= 1e6):
            raise InputError("pressure_pa", f"the {self.kind} target needs a pressure, got "
                             + ("none" if self.pressure_pa is None else repr(self.pressure_pa)),
                             "0 < pressure_pa <= 1e6 Pa")
        name = "force_mn" if self.kind == "force_at_pressure" else "angle_deg"
        value = getattr(self, name)
        if value is None or not _finite(value) or not (_positive(abs(value))
                                                            and abs(value) <= MAX_TARGET[name]):
            unit = "mN" if name == "force_mn" else "deg"
            raise InputError(name, f"the {self.kind} target needs a non-zero {name} of "
                             f"at most {MAX_TARGET[name]:g} {unit}, got "
                             + ("none" if value is None else repr(value)),
                             f"0 < |{name}| <= {MAX_TARGET[name]:g} {unit}; "
                             "positive bends away from the membrane, negative towards it")
        other = "angle_deg" if name == "force_mn" else "force_mn"
        if getattr(self, other) is not None:    # given, never silently dropped
            raise InputError(other, f"the {self.kind} target does not use {other}",
                             f"leave {other} out (the {self.kind} target takes {name})")
        return self

    def _fields(self) -> tuple[str, ...]:
        """The fields besides the angle (or force) this kind of target reads."""
        if self.kind in TIME_KINDS:
            return ("time_s", "flow_ul_s")
        return ("volume_ul",) if self.kind in VOLUME_KINDS else ("pressure_pa",)

    def _check_time(self) -> None:
        """time_s and flow_ul_s given, in range, and injecting no more than the FE's
        volume stop (time x flow, from the undeformed state)."""
        if self.flow_ul_s is None or not _finite(self.flow_ul_s) or not (
                MIN_FLOW_UL_S <= self.flow_ul_s <= MAX_FLOW_UL_S):
            raise InputError("flow_ul_s", f"the {self.kind} target needs the pump's flow "
                             "rate, got " + ("none" if self.flow_ul_s is None
                                             else repr(self.flow_ul_s)), FLOW_RANGE)
        if not _finite(self.time_s) or not (_positive(self.time_s) and self.time_s <= MAX_TIME_S):
            raise InputError("time_s", f"the {self.kind} target needs a time, got "
                             + ("none" if self.time_s is None else repr(self.time_s)),
                             f"0 < time_s <= {MAX_TIME_S:g} s")
        volume = self.time_s * self.flow_ul_s
        if volume > FE_VOLUME_STOP_UL:
            raise InputError("time_s", f"{self.time_s:g} s at {self.flow_ul_s:g} ul/s "
                             f"injects {volume:g} ul, past the FE's volume stop "
                             f"({FE_VOLUME_STOP_UL:g} ul): no design is answered there",
                             f"0 < time_s <= {FE_VOLUME_STOP_UL / self.flow_ul_s:.4g} s at "
                             f"{self.flow_ul_s:g} ul/s (time_s x flow_ul_s <= "
                             f"{FE_VOLUME_STOP_UL:g} ul)")

    @property
    def value(self) -> float:
        return abs(float(self.force_mn if self.kind == "force_at_pressure"
                         else self.angle_deg))  # type: ignore[arg-type]

    @property
    def by_volume(self) -> bool:
        """A syringe pump's target: met at (or within) an injected volume."""
        return self.kind in VOLUME_KINDS

    @property
    def budget(self) -> bool:
        """Met within a budget (pressure, volume or time), not exactly."""
        return self.kind in BUDGET_KINDS

    @property
    def at(self) -> float:
        """Where the target is met: the pressure (Pa), or for a pump's target the injected
        volume (ul; time x flow for a time target)."""
        if self.kind in TIME_KINDS:
            return float(self.time_s) * float(self.flow_ul_s)  # type: ignore[arg-type]
        return float(self.volume_ul if self.by_volume else self.pressure_pa)  # type: ignore

    @property
    def at_field(self) -> str:
        """The field ``at`` is given by: pressure_pa, volume_ul or time_s."""
        return self._fields()[0]

    def at_text(self, exact: bool = False) -> str:
        """Where the target is met, in words: "at 1500 Pa", "at 20 ul injected", "after 8 s
        at 2.5 ul/s (20 ul injected)"; a budget's "within" unless ``exact``."""
        within = self.budget and not exact
        if self.kind in TIME_KINDS:
            return (f"{'within' if within else 'after'} {self.time_s:g} s at "
                    f"{self.flow_ul_s:g} ul/s ({self.at:.4g} ul injected)")
        where = "within" if within else "at"
        if self.by_volume:
            return f"{where} {self.at:.4g} ul injected"
        return f"{where} {self.at:g} Pa"

    def with_at(self, at: float) -> DesignTarget:
        """The same target met at ``at`` instead (Pa, or ul for a pump's target)."""
        if self.kind in TIME_KINDS:
            return replace(self, time_s=at / float(self.flow_ul_s))  # type: ignore[arg-type]
        return replace(self, **{"volume_ul" if self.by_volume else "pressure_pa": at})

    def as_dict(self) -> dict[str, object]:
        return {"kind": self.kind, "pressure_pa": self.pressure_pa,
                "angle_deg": self.angle_deg, "force_mn": self.force_mn,
                "volume_ul": self.volume_ul, "time_s": self.time_s,
                "flow_ul_s": self.flow_ul_s}


@dataclass(frozen=True)
class DesignBounds:
    """Search space: L and t ranges in mm (None: each family's fitted range, t from
    0.5 mm) and allowed (body, membrane) material id pairs (None: every family)."""

    L_mm: tuple[float, float] | None = None
    t_mm: tuple[float, float] | None = None
    material_pairs: tuple[tuple[str, str], ...] | None = None

    def validated(self) -> DesignBounds:
        for name in ("L_mm", "t_mm"):
            r = getattr(self, name)
            if r is None:
                continue
            if (len(r) != 2 or not all(_finite(v) for v in r) or not 0 < r[0] <= r[1]):
                raise InputError(name, f"bounds {r!r}", "(low, high) with 0 < low <= high mm")
        return self


@dataclass(frozen=True)
class DesignCandidate:
    """A ranked design: the score of the objective (lower is better), the pressure it
    needs (pressure_budget) or its predicted value at the target pressure, and the
    predicted curve from 0 Pa with its band."""

    rank: int
    design: Design
    family: str
    score: float
    pressure_needed_pa: float
    pressure_lower_pa: float
    pressure_upper_pa: float
    value_at_pressure: float
    value_lower: float
    value_upper: float
    curve: Prediction
    # the value's change (deg or mN) when one length is made 0.01 mm larger, the others
    # kept: a mould's tolerance read on the answer (design-space search; None otherwise)
    change_per_0_01_mm: dict[str, float] | None = None
    # a syringe pump's target (surrogate.pump_targets.volume_report; None otherwise): the
    # injected volume needed for the angle with its band (ul), the time at the target's
    # flow rate (s), and at the target volume the angle with its band (deg) and the
    # chamber pressure (Pa)
    volume_needed_ul: float | None = None
    volume_lower_ul: float | None = None
    volume_upper_ul: float | None = None
    time_needed_s: float | None = None
    time_lower_s: float | None = None
    time_upper_s: float | None = None
    angle_at_volume_deg: float | None = None
    angle_at_volume_lower_deg: float | None = None
    angle_at_volume_upper_deg: float | None = None
    pressure_at_volume_pa: float | None = None

    def as_dict(self) -> dict[str, object]:
        from solver.design_space import recognise

        def preset_and_scale(material: object) -> tuple[str, float]:
            found = recognise(material)  # type: ignore[arg-type]
            return found if found is not None else (material.id, 1.0)  # type: ignore

        body, s_body = preset_and_scale(self.design.body_material)
        membrane, s_membrane = preset_and_scale(self.design.membrane_material)
        return {"rank": self.rank, "L_mm": self.design.L_mm, "t_mm": self.design.t_mm,
                "T_mm": self.design.T_mm, "b_mm": self.design.b_mm, "h_mm": self.design.h_mm,
                "body_material": body, "membrane_material": membrane,
                "body_stiffness_scale": s_body, "membrane_stiffness_scale": s_membrane,
                "design": self.design.as_dict(),
                "family": self.family, "score": self.score,
                "pressure_needed_pa": self.pressure_needed_pa,
                "pressure_lower_pa": self.pressure_lower_pa,
                "pressure_upper_pa": self.pressure_upper_pa,
                "value_at_pressure": self.value_at_pressure, "value_lower": self.value_lower,
                "value_upper": self.value_upper,
                "change_per_0_01_mm": self.change_per_0_01_mm,
                **{name: getattr(self, name) for name in PUMP_FIELDS},
                "validity": self.curve.validity,
                "curve": {k: v for k, v in self.curve.as_dict().items()
                          if k in ("pressure_pa", "angle_deg", "lower_deg", "upper_deg",
                                   "force_mn", "force_lower_mn", "force_upper_mn",
                                   "volume_ul")}}


@dataclass(frozen=True)
class InverseDesignResult:
    """Ranked feasible designs, or an explanation (``feasible`` False) with the largest
    value reachable at the target pressure inside the bounds (``best_reachable``)."""

    target: DesignTarget
    objective: str
    feasible: bool
    candidates: tuple[DesignCandidate, ...]
    explanation: str
    best_reachable: dict = field(default_factory=dict)
    n_evaluated: int = 0
    model: str = ""

    def as_dict(self) -> dict[str, object]:
        return {"target": self.target.as_dict(),
                "objective": self.objective, "feasible": self.feasible,
                "candidates": [c.as_dict() for c in self.candidates],
                "explanation": self.explanation, "best_reachable": dict(self.best_reachable),
                "n_evaluated": self.n_evaluated, "model": self.model}


def _finite(v: object) -> bool:
    return isinstance(v, (int, float)) and np.isfinite(v)


def _positive(v: float) -> bool:
    """More than 0, a subnormal magnitude (5e-324 ul, 1e-310 deg) counting as 0."""
    return v >= SMALLEST_NORMAL


def _families(s: Surrogate, bounds: DesignBounds) -> list[Family]:
    fams = list(s.family_fits)
    if bounds.material_pairs is None:
        return fams
    known = {(f.body_material.id, f.membrane_material.id) for f in fams}
    for pair in bounds.material_pairs:
        if tuple(pair) not in known:
            raise InputError("material_pairs", f"no fitted family for {pair[0]}/{pair[1]}",
                             ", ".join(f"{b}/{m}" for b, m in sorted(known)))
    wanted = {tuple(p) for p in bounds.material_pairs}
    return [f for f in fams if (f.body_material.id, f.membrane_material.id) in wanted]


def _ranges(fam: Family, bounds: DesignBounds) -> tuple[tuple[float, float], tuple[float, float]]:
    L = bounds.L_mm or fam.domain.L_mm
    if bounds.t_mm is not None:
        t = bounds.t_mm
    else:
        lo, hi = fam.domain.t_mm
        t = (max(lo, TWO_BALLOON_BELOW_t_MM), hi) if hi >= TWO_BALLOON_BELOW_t_MM else (lo, hi)
    return (float(L[0]), float(L[1])), (float(t[0]), float(t[1]))


@dataclass
class _Eval:
    L: np.ndarray
    t: np.ndarray
    score: np.ndarray
    p: np.ndarray
    p_lo: np.ndarray
    p_hi: np.ndarray
    v: np.ndarray
    v_lo: np.ndarray
    v_hi: np.ndarray


def _evaluate(par: ModelParameters, target: DesignTarget, objective: str, L: np.ndarray,
              t: np.ndarray, level: float) -> _Eval:
    """Metrics for candidate (L, t) arrays; infeasible candidates score +inf."""
    th = par.theta
    P = float(target.pressure_pa)
    sign = 1.0 if th[0] > 0 else -1.0
    ok = equations.tau_pa(th, t) > 0
    with np.errstate(all="ignore"):
        if target.kind == "pressure_budget":
            p, half = bands.pressure_band(par, L, t, np.full_like(L, sign * target.value), level)
            p_lo, p_hi = p - half, p + half
            ok &= np.isfinite(p) & (p <= P)
        else:
            L = np.where(ok, equations.length_mm(th, t, P, target.value), np.nan)
            p = np.full_like(L, P)
            p_lo = p_hi = p
            ok &= np.isfinite(L)
        v, v_lo, v_hi = bands.angle_band(par, L, t, P, level)
        vh = 0.5 * (v_hi - v_lo)
        score = {"pressure": p, "margin": p_hi, "compact": L + 1e-9 * p,
                 "certainty": 2 * vh / np.abs(v)}[objective]
    score = np.where(ok & np.isfinite(score), score, np.inf)
    return _Eval(L, t, score, p, np.maximum(p_lo, 0.0), p_hi, v, v - vh, v + vh)


def _grid(fam: Family, par: ModelParameters, target: DesignTarget, objective: str,
          Lr: tuple[float, float], tr: tuple[float, float], level: float, n: int) -> _Eval:
    if target.kind == "pressure_budget":
        Lg, tg = np.meshgrid(np.linspace(*Lr, n), np.linspace(*tr, n), indexing="ij")
        return _evaluate(par, target, objective, Lg.ravel(), tg.ravel(), level)
    t = np.linspace(*tr, n * n)
    e = _evaluate(par, target, objective, np.zeros_like(t), t, level)
    e.score = np.where((e.L >= Lr[0] - 1e-12) & (e.L <= Lr[1] + 1e-12), e.score, np.inf)
    return e


def _refine(fam: Family, par: ModelParameters, target: DesignTarget, objective: str,
            Lr: tuple[float, float], tr: tuple[float, float], level: float, n: int,
            best: int, e: _Eval) -> _Eval:
    dL = (Lr[1] - Lr[0]) / max(n - 1, 1)
    if target.kind == "pressure_budget":
        dt = (tr[1] - tr[0]) / max(n - 1, 1)
        L0, t0 = e.L[best], e.t[best]
        sub_L = (max(Lr[0], L0 - dL), min(Lr[1], L0 + dL))
        sub_t = (max(tr[0], t0 - dt), min(tr[1], t0 + dt))
        return _grid(fam, par, target, objective, sub_L, sub_t, level, 15)
    dt = (tr[1] - tr[0]) / max(n * n - 1, 1)
    t0 = e.t[best]
    return _grid(fam, par, target, objective, Lr, (max(tr[0], t0 - dt), min(tr[1], t0 + dt)),
                 level, 7)


def _concat(evals: list[_Eval]) -> _Eval:
    return _Eval(*(np.concatenate([getattr(e, f) for e in evals])
                   for f in ("L", "t", "score", "p", "p_lo", "p_hi", "v", "v_lo", "v_hi")))


def inverse_design(surrogate: Surrogate, target: DesignTarget,
                   bounds: DesignBounds | None = None, *, objective: str | None = None,
                   n_results: int = 5, level: float = 0.95,
                   grid: int = GRID) -> InverseDesignResult:
    """Feasible designs for ``target`` inside ``bounds`` ranked by ``objective``, or an
    explanation of why none is feasible. See the module docstring."""
    target = target.validated()
    if target.by_volume:
        raise InputError("kind", f"the family grid searches by pressure only, not "
                         f"{target.kind}", "angle_at_pressure | pressure_budget | "
                         "force_at_pressure here; surrogate.design_search for a pump's target")
    bounds = (bounds or DesignBounds()).validated()
    objective = resolve_objective(target, objective)
    if not 1 <= n_results <= 50:
        raise InputError("n_results", f"got {n_results!r}", "1 <= n_results <= 50")
    if not 4 <= grid <= 400:
        raise InputError("grid", f"got {grid!r}", "4 <= grid <= 400")
    z_value(level)
    per_family: list[tuple[Family, ModelParameters, _Eval, tuple, tuple]] = []
    n_eval = 0
    for fam in _families(surrogate, bounds):
        par = fam.force if target.kind == "force_at_pressure" else surrogate._params(fam, None)
        if par is None:
            continue
        Lr, tr = _ranges(fam, bounds)
        e = _grid(fam, par, target, objective, Lr, tr, level, grid)
        n_eval += e.score.size
        best = int(np.argmin(e.score))
        if np.isfinite(e.score[best]):
            r = _refine(fam, par, target, objective, Lr, tr, level, grid, best, e)
            n_eval += r.score.size
            e = _concat([r, e])
        per_family.append((fam, par, e, Lr, tr))
    if not per_family:
        what = "force curves" if target.kind == "force_at_pressure" else "families"
        raise InputError("target", f"surrogate '{surrogate.name}' has no {what} for this "
                         "target", "a surrogate fitted from records with that data")
    picked = _pick(per_family, n_results)
    candidates = tuple(_candidate(surrogate, i + 1, fam, par, e, j, target, level)
                       for i, (fam, par, e, j, Lr, tr) in enumerate(picked))
    if candidates:
        return InverseDesignResult(target, objective, True, candidates,
                                   f"{len(candidates)} feasible design(s), ranked by "
                                   f"{objective}", n_evaluated=n_eval, model=surrogate.name)
    reach = _best_reachable(per_family, target)
    return InverseDesignResult(target, objective, False, (), str(reach.pop("explanation")),
                               reach,
                               n_evaluated=n_eval, model=surrogate.name)


def _pick(per_family: list, n: int) -> list:
    """Greedy: the best remaining score, then drop its neighbours in the same family
    (closer than MIN_SPACING in L, t normalised by the bounds); n times."""
    score, fam_i, xL, xt, idx = [], [], [], [], []
    for k, (_, _, e, Lr, tr) in enumerate(per_family):
        score.append(e.score)
        fam_i.append(np.full(e.score.size, k))
        xL.append((e.L - Lr[0]) / max(Lr[1] - Lr[0], 1e-9))
        xt.append((e.t - tr[0]) / max(tr[1] - tr[0], 1e-9))
        idx.append(np.arange(e.score.size))
    s, f, a, b, j_all = (np.concatenate(v) for v in (score, fam_i, xL, xt, idx))
    s = s.copy()
    chosen = []
    for _ in range(n):
        j = int(np.argmin(s))
        if not np.isfinite(s[j]):
            break
        fam, par, e, Lr, tr = per_family[f[j]]
        chosen.append((fam, par, e, int(j_all[j]), Lr, tr))
        near = (f == f[j]) & (np.hypot(a - a[j], b - b[j]) < MIN_SPACING)
        s[near] = np.inf
    return chosen


def _design(fam: Family, L: float, t: float) -> Design:
    W = fam.domain.W_mm[0] if fam.domain.W_mm else Design().W_mm
    return replace(Design(), L_mm=float(L), t_mm=float(t), T_mm=fam.T_mm, b_mm=fam.b_mm,
                   h_mm=fam.h_mm, W_mm=W, body_material=fam.body_material,
                   membrane_material=fam.membrane_material)


def _candidate(s: Surrogate, rank: int, fam: Family, par: ModelParameters, e: _Eval, j: int,
               target: DesignTarget, level: float) -> DesignCandidate:
    design = _design(fam, e.L[j], e.t[j])
    top = max(target.pressure_pa, float(e.p_hi[j]) if np.isfinite(e.p_hi[j]) else 0.0)
    curve = s.predict(design, np.linspace(0.0, top, CURVE_POINTS), level, form=par.form
                      if target.kind != "force_at_pressure" else None)
    return DesignCandidate(rank, design, fam.label, float(e.score[j]), float(e.p[j]),
                           float(e.p_lo[j]), float(e.p_hi[j]), float(e.v[j]),
                           float(e.v_lo[j]), float(e.v_hi[j]), curve)


def _best_reachable(per_family: list, target: DesignTarget) -> dict[str, object]:
    """Largest |value| at the target pressure within the bounds, and the least pressure
    any design needs for the target (both over the search grid's corners)."""
    unit = "mN" if target.kind == "force_at_pressure" else "deg"
    P = target.pressure_pa
    best = None
    for fam, par, _, Lr, tr in per_family:
        for L in Lr:
            for t in tr:
                if not equations.tau_pa(par.theta, t) > 0:
                    continue
                v = float(equations.angle_deg(par.theta, L, t, P))
                if best is None or abs(v) > abs(best["value"]):
                    best = {"value": v, "L_mm": L, "t_mm": t, "family": fam.label}
    smallest = None
    for fam, par, _, Lr, tr in per_family:
        for L in Lr:
            for t in tr:
                v = float(equations.angle_deg(par.theta, L, t, P))
                if smallest is None or abs(v) < abs(smallest["value"]):
                    smallest = {"value": v, "L_mm": L, "t_mm": t, "family": fam.label}
    out: dict[str, object] = {"largest_at_pressure": best, "smallest_at_pressure": smallest,
                              "unit": unit, "pressure_pa": P}
    if best is None:
        out["explanation"] = "no design inside the bounds has a positive pressure constant"
    elif target.kind != "pressure_budget" and smallest and target.value < abs(
            smallest["value"]):
        out["explanation"] = (
            f"{target.value:g} {unit} at {P:g} Pa is below the smallest value reachable inside "
            f"the bounds, {abs(smallest['value']):.3g} {unit} (L = {smallest['L_mm']:g} mm, "
            f"t = {smallest['t_mm']:g} mm): lower the pressure or widen the bounds")
    else:
        out["explanation"] = (
            f"{target.value:g} {unit} is not reachable at {P:g} Pa inside the bounds: the "
            f"largest is {abs(best['value']):.3g} {unit} (L = {best['L_mm']:g} mm, t = "
            f"{best['t_mm']:g} mm, {best['family']}); raise the pressure, allow a longer "
            "chamber or a thinner membrane")
    return out
