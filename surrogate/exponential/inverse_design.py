"""Inverse design with the exponential model: which (material pair, L, t) of its fitted
families meets a target by pressure, ranked by an objective (targets and objectives:
``surrogate.search.design_target``; the answer: ``surrogate.search.design_result``).

    angle_at_pressure   for each t the chamber length is closed form,
                        L = |angle| / (|a| (exp(x + c x^2) - 1)), x = p / tau(t)
                        (``equations.length_mm``); candidates are the (L, t) with L inside
                        the bounds.
    pressure_budget     the pressure needed, p = tau x with x + c x^2 = ln(1 + |angle| / |A|)
                        (``bands.pressure_band``), on an L x t grid.
    force_at_pressure   as angle_at_pressure with the family's force model (mN).

A syringe pump's targets are searched over the box by ``surrogate.search.design_search`` only;
this family grid refuses them. Angles are matched in magnitude: a reversed material pair
(a < 0) is a candidate too, and its predictions carry the negative sign. The margin
objective is the largest margin to the budget at the band's pessimistic end.

Evaluation is vectorised over a grid (per family), the best cell is refined on a finer
local grid, and the ranked list keeps designs at least ``MIN_SPACING`` apart (normalised
L, t). Bounds default to each family's fitted domain, with t >= 0.5 mm (no two-balloon
designs unless the bounds ask for them). Lengths in mm, pressures in Pa, angles in deg.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from solver.design import Design
from solver.errors import InputError
from surrogate.band_level import z_value
from surrogate.exponential import bands, equations
from surrogate.exponential.family import Family
from surrogate.exponential.paper_tables import TWO_BALLOON_BELOW_t_MM
from surrogate.exponential.parameters import ModelParameters
from surrogate.exponential.surrogate import Surrogate
from surrogate.search.design_result import DesignCandidate, InverseDesignResult
from surrogate.search.design_target import DesignTarget, finite_number, resolve_objective

#: the least distance between two listed designs of one family, in (L, t) normalised by
#: the bounds
MIN_SPACING = 0.08
#: grid points per axis (angle_at_pressure: GRID^2 membrane thicknesses)
GRID = 48
#: points of each listed design's curve, from 0 Pa to the target (or needed) pressure
CURVE_POINTS = 41


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
            if (len(r) != 2 or not all(finite_number(v) for v in r) or not 0 < r[0] <= r[1]):
                raise InputError(name, f"bounds {r!r}", "(low, high) with 0 < low <= high mm")
        return self


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
    """The grid's cells: chamber length ``L`` and membrane thickness ``t`` (mm), the
    objective's ``score`` (+inf where infeasible), the pressure needed ``p`` with its
    band (Pa), the value at the target pressure ``v`` with its band (deg, or mN for a
    force target)."""

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
                         "force_at_pressure here; surrogate.search.design_search for a "
                         "pump's target")
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
