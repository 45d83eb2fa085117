"""The force band's calibration on FE curves of random blocked-tip designs of the box.

The force band is the force GP's sd times a multiplier from 5-fold cross-validation over
the database (``force_fit.force_band_scale``), carried through the free tip's angle band
(``features.force_from_angle_ratio``). Cross-validated, |error| / sd has a heavy tail
(database designs on the box's faces are extrapolations when left out), and the 95 %
bands so made covered 0.98-0.99 of the points of 38 held-out random blocked-tip FE curves
(``benchmarks/heldout/force3040.h5``; 0.993 after the face designs of the forty-third
session): wider than a 95 % band should be, by some 1.4 x in the half-width. A user's
design is a random design of the box, so, as the angle bands are
(``random_calibration``), the force band is calibrated once more on FE curves of random
designs that are in neither the database nor the held-out test sets:

for every FE point of those curves (complete, or up to the step an early-ended one
reached) the answer gives a force at (|F| > FORCE_MIN_MN), the
factor by which its band's half-width on the FE point's side would have to change to reach
it; the ``level`` quantile of those factors multiplies the group's half-widths
(``PairEmulator.force_band_factor``, never below FACTOR_MIN). A group (and bending sign)
takes the factor of its own points when it has GROUP_MIN_POINTS of them on
GROUP_MIN_CURVES curves; the others the pooled factor, found with every group at it over
every group's points. The force is withheld where its band is wider than
``force_answer.FORCE_BAND_LIMIT`` x the force, so which points are answered depends on the
factor: each factor is found in rounds, each measuring at the points the current factor
answers (``cell_factor``; a first version multiplied all groups at once and, the pooled
quantile mixing groups at different factors, had not settled after 4 rounds: 0.62
where the fixed point was 0.56).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from solver.design_space import locate
from solver.errors import InputError
from solver.settings import SolverSettings
from surrogate.band_level import z_value
from surrogate.emulator.emulator import Emulator

FORCE_MIN_MN = 1e-3         # FE points with a smaller |force| are not counted (sensor floor)
FACTOR_MIN = 0.5            # a band is narrowed at most 2 x
# a group's own factor from this many points on this many curves (the angle calibration's
# 120 points; points of one curve are not independent). With 60 on 8 Ecoflex on Ecoflex
# took its own 0.57 and the held-out force3040 curves' coverage fell to 0.907
GROUP_MIN_POINTS = 120
GROUP_MIN_CURVES = 15
ROUNDS = 8
TOLERANCE = 0.005       # a factor that moves less than this in a round is found


def blocked_default(settings: SolverSettings) -> bool:
    """Whether ``settings`` are the default FE's with the tip held (any pressure stop)."""
    default = SolverSettings()
    return settings.tip == "blocked" and replace(
        settings, tip=default.tip, max_pressure_pa=default.max_pressure_pa) == default


@dataclass(frozen=True)
class ForceFactors:
    """Per FE point the answer gives a force at: the factor its band's half-width would
    need (<= 1: inside), the emulator group and the curve (index among the records)."""

    factor: np.ndarray
    pair: np.ndarray
    curve: np.ndarray


def force_point_factors(emulator: Emulator, records: list, level: float = 0.95
                        ) -> ForceFactors:
    """The factors of every FE point of the blocked-tip default-FE ``records`` at which
    ``emulator`` gives a force (designs it refuses or gives no force for are skipped)."""
    z = z_value(level)
    cols: dict[str, list] = {"factor": [], "pair": [], "curve": []}
    for index, rec in enumerate(records):
        if not blocked_default(rec.settings) or len(rec.curve.pressure_pa) < 2:
            continue
        c = rec.curve
        keep = (c.pressure_pa > 0) & (np.abs(c.force_mn) > FORCE_MIN_MN)
        if not keep.any():
            continue
        try:
            pair = emulator.curve_band(locate(rec.design, reduced=True), z)[0].pair
            answer = emulator.predict(rec.design, c.pressure_pa[keep], level)
        except InputError:
            continue
        if answer.force_mn is None:
            continue
        fe, f = c.force_mn[keep], answer.force_mn
        given = np.isfinite(f)
        fe, f = fe[given], f[given]
        lo, hi = answer.force_lower_mn[given], answer.force_upper_mn[given]
        half = np.where(fe > f, hi - f, f - lo)
        factor = np.abs(fe - f) / np.maximum(half, 1e-300)
        cols["factor"].append(factor)
        cols["pair"].append(np.full(len(factor), pair))
        cols["curve"].append(np.full(len(factor), index))
    if not cols["factor"]:
        return ForceFactors(np.zeros(0), np.zeros(0, str), np.zeros(0, int))
    return ForceFactors(*(np.concatenate(cols[k]) for k in ("factor", "pair", "curve")))


def coverage(ff: ForceFactors) -> dict:
    """Per group and over all: the share of the force points inside their band, and how
    many points and curves it stands on."""
    out = {"all": {"coverage": float(np.mean(ff.factor <= 1.0)) if len(ff.factor) else None,
                   "points": int(len(ff.factor)), "curves": int(len(np.unique(ff.curve)))}}
    for pair in sorted(set(ff.pair.tolist())):
        s = ff.pair == pair
        out[pair] = {"coverage": float(np.mean(ff.factor[s] <= 1.0)),
                     "points": int(s.sum()), "curves": int(len(np.unique(ff.curve[s])))}
    return out


def _with_factor(emulator: Emulator, keys: Iterable[str], factor: float) -> Emulator:
    """``emulator`` with the force band factor of the groups ``keys`` set to ``factor``."""
    keys = set(keys)
    return replace(emulator, pairs={k: replace(pe, force_band_factor=factor) if k in keys
                                    else pe for k, pe in emulator.pairs.items()})


def cell_factor(emulator: Emulator, records: list, keys: Iterable[str], level: float
                ) -> tuple[float, int]:
    """The factor that, set for every group of ``keys``, makes the ``level`` quantile of
    those groups' point factors 1 (each round multiplies it by that quantile, from the
    groups' current factor, until it moves less than TOLERANCE or after ROUNDS), never
    below FACTOR_MIN; and the rounds taken."""
    keys = tuple(keys)
    factor = float(np.median([emulator.pairs[k].force_band_factor for k in keys]))
    for rounds in range(1, ROUNDS + 1):
        ff = force_point_factors(_with_factor(emulator, keys, factor), records, level)
        mine = np.isin(ff.pair, keys)
        if not mine.any():
            return factor, rounds
        new = max(FACTOR_MIN, factor * float(np.quantile(ff.factor[mine], level)))
        moved = abs(new / factor - 1.0)
        factor = new
        if moved < TOLERANCE:
            break
    return factor, rounds


def own_groups(ff: ForceFactors) -> list[str]:
    """The groups with GROUP_MIN_POINTS force points on GROUP_MIN_CURVES curves: they
    take their own factor, the others the pooled one."""
    out = []
    for pair in sorted(set(ff.pair.tolist())):
        mine = ff.pair == pair
        if (mine.sum() >= GROUP_MIN_POINTS
                and len(np.unique(ff.curve[mine])) >= GROUP_MIN_CURVES):
            out.append(pair)
    return out


def calibrate_force_on_random_designs(emulator: Emulator, records: Iterable,
                                      level: float = 0.95, source: dict | None = None
                                      ) -> Emulator:
    """The emulator with every group's force band half-widths scaled by the factor from
    the blocked-tip FE curves of random designs among ``records`` (module docstring):
    the pooled factor found with every group at it, over every group's points; a group
    with points enough of its own (``own_groups``) its own factor over its own points.
    The report gains ``random_design_force_calibration`` (factors, coverage before and
    after). Unchanged, with the report saying so, when ``records`` hold no such curve."""
    records = [r for r in records if blocked_default(r.settings)]
    report = dict(emulator.report)
    before = force_point_factors(emulator, records, level) if records else None
    if before is None or not len(before.factor):
        report["random_design_force_calibration"] = {
            "curves": len(records), "note": "no blocked-tip FE curves of random designs "
            "with a force answered: the force bands are those of the cross-validation over "
            "the database"}
        return replace(emulator, report=report)
    with_force = [k for k, pe in emulator.pairs.items() if pe.force is not None]
    pooled, pooled_rounds = cell_factor(emulator, records, with_force, level)
    own = [k for k in own_groups(before) if k in with_force]
    factors = {k: pooled for k in with_force}
    rounds = {"pooled": pooled_rounds}
    for key in own:
        factors[key], rounds[key] = cell_factor(emulator, records, [key], level)
    calibrated = replace(emulator, pairs={
        k: replace(pe, force_band_factor=factors.get(k, pe.force_band_factor))
        for k, pe in emulator.pairs.items()})
    after = force_point_factors(calibrated, records, level)
    report["random_design_force_calibration"] = {
        "level": level, "curves": len(records), "factor_min": FACTOR_MIN,
        "factors": factors, "factor_source": {k: "own" if k in own else "pooled"
                                              for k in factors},
        "pooled_factor": pooled, "rounds": rounds,
        "coverage_before": coverage(before), "coverage_after": coverage(after),
        "source": dict(source or {})}
    return replace(calibrated, report=report)
