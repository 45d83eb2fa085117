"""The bands' second calibration: on FE curves of random designs of the box.

The fit calibrates each group's band multipliers by 5-fold cross-validation over the
database (``band_scales.node_band_scales``). Those bands covered 0.97-0.985 of the
cross-validated points but only 0.83-0.96 of the points of held-out random designs drawn
uniformly in the box (each layer's stiffness scaled on its own), and 0.71-0.78 of those
within NEAR_FAILED_RADIUS of a curve that ended early (benchmarks/RESULTS.md, eleventh and
twelfth sessions): the database's designs (Sobol rounds, adaptive points, PDMS twins)
stand closer to one another than a random design stands to them. A user's design is such
a random design, so the bands are calibrated once more on FE curves of random designs
that are in neither the database nor the held-out test sets:

for every answered FE point (deg, at the FE's own pressure or injected volume) the factor
by which the band's half-width (log p, or log V, at the FE angle) would have to grow to
reach it; per angle bin (``band_scales.ANGLE_BINS_DEG``), separately for designs near an
early-ended curve and the others, the ``level`` quantile of those factors (never below 1)
multiplies the nodes' band multipliers of that bin: the far factor into ``band_scale``,
the near one's excess over it into ``near_failed_band_scale``. A cell with fewer than
MIN_CELL_POINTS points pools its neighbouring bins until it has them. Each group (and
bending sign) gets the factors of its own points where it has GROUP_MIN_POINTS of them on
that axis and side, and the factors of every group's points pooled otherwise. Until
2026-12-04 every group took the pooled factors: on the balanced database the volume
band of far designs at 20-40 deg was widened 7.97x for all because of 14 points of the
reversed-bending Ecoflex/Ecoflex group, while for the rest that band stood some 50x wider
than their errors (benchmarks/RESULTS.md).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from solver.design_space import locate
from solver.errors import InputError
from solver.settings import SolverSettings
from surrogate.band_level import z_value
from surrogate.emulator.band_scales import ANGLE_BINS_DEG, angle_bin
from surrogate.emulator.curve_band import volume_curves
from surrogate.emulator.emulator import Emulator
from surrogate.emulator.features import (
    ANGLE_BAND_FLOOR_DEG,
    ANGLE_NODES_DEG,
    FINE_ANGLES_DEG,
    N_NODES,
)
from surrogate.emulator.node_curves import ANGLES0, _with_origin
from surrogate.emulator.pair_emulator import NEAR_FAILED_RADIUS

MIN_CELL_POINTS = 40
GROUP_MIN_POINTS = 3 * MIN_CELL_POINTS     # a group's own factors from this many points
AXES = ("pressure", "volume")


@dataclass(frozen=True)
class PointFactors:
    """Per answered FE point of the calibration curves: |FE angle| (deg), the factor its
    band would need (<= 1: inside), whether its design is near an early-ended curve, the
    axis (pressure or volume), the emulator group and the curve (its index among the
    calibration records)."""

    angle_deg: np.ndarray
    factor: np.ndarray
    near: np.ndarray
    axis: np.ndarray
    pair: np.ndarray
    curve: np.ndarray


def _needed(x_fe: np.ndarray, theta: np.ndarray, mean: np.ndarray, low: np.ndarray,
            high: np.ndarray) -> np.ndarray:
    """The factor on the band's log half-width that reaches each FE point (x_fe, theta):
    x is p or V (reduced), the curves x(theta) on ANGLES0 (origin first). A point within
    ANGLE_BAND_FLOOR_DEG of the answer is inside at any factor (the band's floor)."""
    t = np.clip(theta, FINE_ANGLES_DEG[0], FINE_ANGLES_DEG[-1])
    lm, ll, lh = (np.log(np.interp(t, ANGLES0[1:], c[1:])) for c in (mean, low, high))
    d = np.log(x_fe) - lm
    half = np.where(d > 0, lh - lm, lm - ll)
    factor = np.abs(d) / np.maximum(half, 1e-12)
    answer = np.interp(x_fe, mean, ANGLES0)
    return np.where(np.abs(answer - theta) <= ANGLE_BAND_FLOOR_DEG, 0.0, factor)


def point_factors(emulator: Emulator, records: Iterable, level: float = 0.95
                  ) -> PointFactors:
    """The factors of every answered FE point of the free-tip default-FE ``records``
    (designs the emulator refuses or answers by its balance model are skipped), by
    pressure and by injected volume."""
    z = z_value(level)
    default = SolverSettings()
    cols: dict[str, list] = {k: [] for k in ("angle", "factor", "near", "axis", "pair",
                                             "curve")}
    for index, rec in enumerate(records):
        if rec.settings != default:
            continue
        try:
            point = locate(rec.design, reduced=True)
            if emulator.balance_model_for(point) is not None:
                continue            # answered by the balance model, its own band
            pe, cb = emulator.curve_band(point, z)
        except InputError:
            continue
        c = rec.curve
        theta = np.abs(c.angle_deg)
        keep = (theta <= min(90.0, cb.limit_angle_deg)) & (c.pressure_pa > 0) & (theta > 0)
        if not keep.any():
            continue
        theta = theta[keep]
        p_red = c.pressure_pa[keep] / point.pressure_scale
        v_red = c.volume_ul[keep] / point.length_scale**3
        vm, vl, vh = volume_curves(cb, z)
        for axis, x, curves in (
                ("pressure", p_red, tuple(_with_origin(k) for k in (
                    cb.pressure_pa, cb.pressure_lower_pa, cb.pressure_upper_pa))),
                ("volume", v_red, (vm, vl, vh))):
            f = _needed(x, theta, *curves)
            cols["angle"].append(theta)
            cols["factor"].append(f)
            cols["near"].append(np.full(len(f), cb.failed_distance < NEAR_FAILED_RADIUS))
            cols["axis"].append(np.full(len(f), axis))
            cols["pair"].append(np.full(len(f), pe.pair))
            cols["curve"].append(np.full(len(f), index))
    if not cols["angle"]:
        raise InputError("band calibration", "no free-tip default-FE curve of the calibration "
                         "database is answered by the emulator", "random designs of the box")
    return PointFactors(*(np.concatenate(cols[k]) for k in
                          ("angle", "factor", "near", "axis", "pair", "curve")))


def cell_factors(pf: PointFactors, level: float = 0.95, pair: str | None = None) -> dict:
    """Per axis, {"far": [...], "near": [...]}: the factor for each angle bin (the ``level``
    quantile of the cell's point factors, >= 1), the near one counted on top of the far
    one (``near`` = max(1, quantile / far)); of one group's points with ``pair`` (its
    emulator key), of all otherwise."""
    n_bins = len(ANGLE_BINS_DEG) - 1
    bins = angle_bin(pf.angle_deg)
    mine = np.ones(pf.pair.shape, bool) if pair is None else pf.pair == pair
    out: dict = {}
    for axis in AXES:
        sel_axis = mine & (pf.axis == axis)
        out[axis] = {}
        for side, near in (("far", False), ("near", True)):
            factors = []
            sel = sel_axis & (pf.near == near)
            for b in range(n_bins):
                for width in range(n_bins):
                    cell = sel & (np.abs(bins - b) <= width)
                    if cell.sum() >= MIN_CELL_POINTS:
                        break
                factors.append(float(max(1.0, np.quantile(pf.factor[cell], level)))
                               if cell.any() else 1.0)
            out[axis][side] = factors
        out[axis]["near"] = [max(1.0, n / f) for n, f in
                             zip(out[axis]["near"], out[axis]["far"], strict=True)]
    return out


def node_factors(factors: list[float]) -> np.ndarray:
    """The bin factors spread over the angle nodes (N_NODES) by each node's angle bin."""
    return np.asarray(factors)[angle_bin(ANGLE_NODES_DEG)]


def group_cells(pf: PointFactors, pooled: dict, pair: str, level: float = 0.95) -> dict:
    """The factors group ``pair`` takes (``cell_factors`` layout): per axis, its own
    far and near factors where it has GROUP_MIN_POINTS points on that axis and side (the
    near ones only where the far ones are its own too), the ``pooled`` ones otherwise."""
    own = cell_factors(pf, level, pair)
    mine = pf.pair == pair
    out: dict = {}
    for axis in AXES:
        counts = {side: int((mine & (pf.axis == axis) & (pf.near == near)).sum())
                  for side, near in (("far", False), ("near", True))}
        far_own = counts["far"] >= GROUP_MIN_POINTS
        out[axis] = {
            "far": own[axis]["far"] if far_own else pooled[axis]["far"],
            "near": (own[axis]["near"] if far_own and counts["near"] >= GROUP_MIN_POINTS
                     else pooled[axis]["near"])}
    return out


def coverage(pf: PointFactors) -> dict:
    """Share of the points inside their band (factor <= 1), by axis and near / far."""
    out = {}
    for axis in AXES:
        sel = pf.axis == axis
        out[axis] = {"all": float(np.mean(pf.factor[sel] <= 1.0)),
                     "points": int(sel.sum())}
        for side, near in (("far", False), ("near", True)):
            s = sel & (pf.near == near)
            out[axis][side] = float(np.mean(pf.factor[s] <= 1.0)) if s.any() else None
            out[axis][f"{side}_points"] = int(s.sum())
    return out


def group_coverage(pf: PointFactors) -> dict:
    """Per group, axis and side (far, near): the share of its points inside their band,
    and how many points and curves that share stands on (``Emulator`` flags a design
    whose cell covered too little: ``band_undercovers_random_designs``)."""
    out: dict = {}
    for pair in sorted(set(pf.pair.tolist())):
        out[pair] = {}
        for axis in AXES:
            out[pair][axis] = {}
            for side, near in (("far", False), ("near", True)):
                s = (pf.pair == pair) & (pf.axis == axis) & (pf.near == near)
                out[pair][axis][side] = {
                    "coverage": float(np.mean(pf.factor[s] <= 1.0)) if s.any() else None,
                    "points": int(s.sum()), "curves": int(len(np.unique(pf.curve[s])))}
    return out


def calibrate_on_random_designs(emulator: Emulator, records: Iterable, level: float = 0.95,
                                source: dict | None = None) -> Emulator:
    """The emulator with every group's band multipliers scaled by the factors from the
    random designs' FE curves ``records`` (module docstring); the report gains
    ``random_design_calibration`` (factors, coverage before and after, ``source``)."""
    records = list(records)
    before = point_factors(emulator, records, level)
    cells = cell_factors(before, level)
    pairs, by_group = {}, {}
    for key, pe in emulator.pairs.items():
        own = group_cells(before, cells, key, level)
        by_group[key] = own
        far = np.concatenate([node_factors(own[a]["far"]) for a in AXES])
        near = np.concatenate([node_factors(own[a]["near"]) for a in AXES])
        assert far.shape == near.shape == (2 * N_NODES,)
        pairs[key] = replace(pe, band_scale=pe.band_scale * far,
                             near_failed_band_scale=near if (near > 1.0).any() else None)
    calibrated = replace(emulator, pairs=pairs)
    after = point_factors(calibrated, records, level)
    curves = sum(1 for r in records if r.settings == SolverSettings())
    report = dict(emulator.report)
    report["random_design_calibration"] = {
        "level": level, "curves": curves, "bins_deg": list(ANGLE_BINS_DEG),
        "factors": cells, "group_factors": by_group, "coverage_before": coverage(before),
        "coverage_after": coverage(after), "group_coverage_after": group_coverage(after),
        "source": dict(source or {})}
    return replace(calibrated, report=report)
