"""Fit the emulator from the curve database, calibrate its bands, report its accuracy.

    emulator = fit_emulator(records)          # records: iterable of solver.store.Record

Which records count: solved with the default FE (``SolverSettings()``: element, mesh,
control, tolerances, stop criteria) for free-tip curves, and with the blocked-tip
variant of the precompute grid's ``[[sample]]`` tables for force; designs inside the box
(``solver.design_space.locate``). Each record is reduced to the box's terms (pressure /
membrane stiffness scale, volume / length scale^3, force / (stiffness scale x length
scale^2)), so records of scaled copies of a design pool their information.

Curves that end before 90 deg (the FE failed or stopped) are not interpolated; they
limit the range of every query within ``FAILED_RADIUS`` of them (unit-cube distance).
Every query's range also ends where its emulated injected volume reaches the FE's volume
stop (``SolverSettings.max_volume_ul``), as the FE's own curve would.

Bands: the GP's standard deviation times ``band_scale``, one multiplier per output node
(``node_band_scales``: per angle bin for pressure), chosen so that cross-validated bands
(``cross_validated``: 5 folds, each predicted by the emulator refitted without it) cover
``level`` of the held-out FE points in every angle bin; the report gives that coverage in
angle, overall and by angle bin (each database curve predicted by the emulator fitted
without it, read at the curve's own pressures).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, fields, replace

import numpy as np

from solver.design_space import GROUPS, locate
from solver.errors import InputError
from solver.settings import SolverSettings
from surrogate.band_level import z_value
from surrogate.emulator.balance import BalanceModel, fit_balance_model
from surrogate.emulator.blocked_range import (
    NEAR_END_FROM,
    BlockedRange,
    fit_blocked_range,
    near_end_band_scales,
)
from surrogate.emulator.curve_gps import CurveGPs, anchor_index, rise_outputs
from surrogate.emulator.early_ended_nodes import EarlyEndedRows, short_of_the_end
from surrogate.emulator.emulator import Emulator
from surrogate.emulator.features import (
    ANGLE_NODES_DEG,
    FORCE_PRESSURE_NODES_PA,
    N_NODES,
    curve_features,
    force_angle_feature,
    force_features,
)
from surrogate.emulator.force_gps import fit_force_nodewise, nodes_reached
from surrogate.emulator.node_curves import (
    ANGLES0,
    _monotone,
    _with_origin,
    floored_band,
    free_angles_deg,
    node_curves,
)
from surrogate.emulator.pair_emulator import (
    FORCE_FORMS,
    NEAR_FAILED_RADIUS,
    PairEmulator,
    nearest_distance,
)
from surrogate.emulator.shape_gps import (
    TOP_PRESSURE_FROM,
    TOP_PRESSURE_MIN_DESIGNS,
    TOP_SHAPE_NODES_DEG,
    VOLUME_SHAPE_NODES_DEG,
    fit_shape_gps,
)
from surrogate.emulator.stretch_hazard import (
    StretchHazard,
    fit_stretch_hazard,
    reached_hazard,
    stretch_nodes,
)
from surrogate.emulator.variance_nodes import choose as choose_variance_nodes
from surrogate.emulator.vector_gp import MEANS_ONLY, VectorGP, fit_output_gps, fit_vector_gp
from surrogate.emulator.volume_curve import volume_shape

LIMIT_ANGLE_DEG = 90.0            # the default FE's stop (SolverSettings.max_angle_deg)
MIN_DESIGNS = 10
FORCE_SHARE = 0.6                 # of a group's blocked-tip curves its force range keeps


@dataclass
class _Rows:
    u: list
    y: list
    keys: list
    curves: list          # (p_red, v_red, angle) per record, for cross-validation
    failed: list          # (u, end angle, reason)
    failed_end_volume: list  # the FE's last injected volume of each, reduced (ul)
    signs: list
    failed_signs: list
    failed_y: list        # node outputs of the early-ended curves (NaN past their end)
    failed_last_step: list  # the angle each one's last FE step started from (deg)
    by_volume: list       # (u, (v_red, p_red, signed angle)) of every curve (balance.py)
    stretch: list         # stretch_hazard.stretch_nodes of each complete curve (as u)
    hazard: list          # (stretch reached HAZARD_STRETCH, ended in a Newton failure)
                          # of every curve (stretch_hazard.py)


def default_free_settings() -> SolverSettings:
    return SolverSettings()


def is_force_record(settings: SolverSettings) -> bool:
    """A blocked-tip curve of the default FE, solved to at least the emulator's force range
    (any ``max_pressure_pa`` >= the last force node: the grid's default or an older
    database's 6000 Pa)."""
    return (settings.tip == "blocked"
            and settings.max_pressure_pa >= FORCE_PRESSURE_NODES_PA[-1]
            and replace(settings, tip="free", max_pressure_pa=SolverSettings().max_pressure_pa)
            == default_free_settings())


def _collect(records: Iterable) -> tuple[dict, dict, dict]:
    """The records' rows by group: free-tip curves (``_Rows``), blocked-tip force rows
    ((unit coordinates, F / p at the force nodes) per design) and blocked-tip ends
    ((unit coordinates, last pressure reduced Pa, stop reason) per design)."""
    free_settings = default_free_settings()
    free: dict[tuple[str, str], _Rows] = {}
    force: dict = {}
    ends: dict = {}
    for rec in records:
        try:
            point = locate(rec.design, reduced=True)
        except InputError:
            continue
        c = rec.curve
        if rec.settings == free_settings:
            rows = free.setdefault(point.group,
                                  _Rows(*([] for _ in fields(_Rows))))
            f = curve_features(c.pressure_pa / point.pressure_scale,
                               c.volume_ul / point.length_scale**3, c.angle_deg)
            u = point.coordinates()
            rows.by_volume.append((u, (c.volume_ul / point.length_scale**3,
                                       c.pressure_pa / point.pressure_scale, c.angle_deg)))
            rows.hazard.append((reached_hazard(c.max_membrane_stretch),
                                c.status == "failed"))
            if f.end_angle_deg < LIMIT_ANGLE_DEG or not np.isfinite(f.log_p).all():
                rows.failed.append((u.tolist(), min(f.end_angle_deg, LIMIT_ANGLE_DEG),
                                    c.reason))
                rows.failed_end_volume.append(float(np.max(c.volume_ul))
                                              / point.length_scale**3)
                rows.failed_signs.append(f.sign)
                rows.failed_y.append(np.concatenate((f.log_p, f.log_v)))
                rows.failed_last_step.append(f.last_step_from_deg)
                continue
            rows.u.append(u)
            rows.y.append(np.concatenate((f.log_p, f.log_v)))
            rows.keys.append(rec.key)
            rows.curves.append((c.pressure_pa / point.pressure_scale,
                                c.volume_ul / point.length_scale**3, c.angle_deg))
            rows.signs.append(f.sign)
            rows.stretch.append(stretch_nodes(c.angle_deg, c.max_membrane_stretch))
        elif is_force_record(rec.settings):
            y = force_features(c.pressure_pa / point.pressure_scale,
                               c.force_mn / (point.pressure_scale * point.length_scale**2))
            if np.isfinite(y[0]):
                # one row per design: a design solved to two pressure limits (an older
                # database's 6000 Pa and today's) keeps the curve that reaches further
                rows_f = force.setdefault(point.group, {})
                key = tuple(np.round(point.coordinates(), 9))
                if key not in rows_f or np.isfinite(y).sum() > np.isfinite(rows_f[key]).sum():
                    rows_f[key] = y
                    ends.setdefault(point.group, {})[key] = (
                        float(c.pressure_pa[-1] / point.pressure_scale), c.reason)
    force = {g: ([np.array(k) for k in rows_f], list(rows_f.values()))
             for g, rows_f in force.items()}
    ends = {g: (np.array(list(e)), np.array([v[0] for v in e.values()]),
                [v[1] for v in e.values()]) for g, e in ends.items()}
    return free, force, ends


ANGLE_BINS_DEG = (0.0, 10.0, 20.0, 40.0, 60.0, 75.0, 90.0)   # band calibration bins


MIN_BAND_SCALE = 1.0              # band multipliers: never below the GP's own sd
CV_FOLDS = 5                      # band calibration: K-fold cross-validation
GEOMETRY_COORDINATES = 5          # the first five unit-cube coordinates: L, t, T, b, h


def fit_curve_gps(u: np.ndarray, y: np.ndarray, seed: int = 0,
                  early_u: np.ndarray | None = None, early_y: np.ndarray | None = None,
                  early_last_step_deg: np.ndarray | None = None) -> CurveGPs:
    """The curve GPs of a group from node outputs ``y`` (n, 64) of its complete curves:
    the 32 pressure nodes share one kernel (a query's band is one product over the
    database, not one per node), each volume node has its own, the volume nodes above 30
    deg as the log of their rise in log V (``curve_gps``); the volume nodes and the
    pressure nodes from 45 deg up are read with the pressure curve's shape too
    (``shape_gps``: the top pressure nodes' GPs share one kernel, the volume nodes' not;
    the top ones only from TOP_PRESSURE_MIN_DESIGNS designs).
    On the FE curves of 252 random designs (benchmarks/RESULTS.md, nineteenth session)
    one kernel for the pressure nodes put 190 curves within the per-curve target where
    one per node put 188. With the early-ended curves' coordinates ``early_u``, node
    outputs ``early_y`` (NaN past their end) and ``early_last_step_deg`` (all three, or
    none), their means for designs emulated to end early (``early_ended_nodes``; each
    curve short of its last reached node where that lies in the FE's last step, which
    started at ``early_last_step_deg``)."""
    anchor = anchor_index()
    early = None
    if early_u is not None and early_y is not None and early_last_step_deg is not None \
            and len(early_u):
        z = rise_outputs(short_of_the_end(early_y, N_NODES, early_last_step_deg), anchor)
        reached = np.isfinite(z[:, 0])
        if reached.any():
            early = EarlyEndedRows(np.asarray(early_u, float)[reached], z[reached])
    z = rise_outputs(y, anchor)
    gp = fit_output_gps(u, z, seed=seed, shared=slice(0, N_NODES))
    volume = fit_shape_gps(u, z[:, N_NODES:], gp, VOLUME_SHAPE_NODES_DEG, shared=False,
                           seed=seed)
    top = None
    if len(u) >= TOP_PRESSURE_MIN_DESIGNS:
        top = fit_shape_gps(u, z[:, TOP_PRESSURE_FROM:N_NODES], gp, TOP_SHAPE_NODES_DEG,
                            shared=True, seed=seed)
    return CurveGPs(gp, anchor, early, volume, top)


def fit_force_gps(u: np.ndarray, y: np.ndarray, seed: int = 0) -> VectorGP:
    """The force GPs of a group: one per force node, all sharing one kernel. A few
    principal components of the nodes (until 2026-12-04) tied the ratio at 25-100 Pa,
    where the blocked tip's small initial reaction can have the other sign, to the nodes
    above: on 52 blocked-tip FE curves of random designs (benchmarks/RESULTS.md, twentieth
    session) the median relative force error went 0.15 -> 0.08 for the reversed pair and 0.28 ->
    0.11 for Ecoflex on Ecoflex; one kernel rather than one per node keeps F / theta smooth
    along the curve (the same medians, the 90th percentile 0.23 -> 0.18 for the reversed
    pair) and a query's band one product."""
    return fit_output_gps(u, y, seed=seed, shared=slice(None))


def cross_validated(u: np.ndarray, y: np.ndarray, seed: int = 0, folds: int = CV_FOLDS,
                    fit=fit_curve_gps) -> tuple[np.ndarray, np.ndarray]:
    """K-fold cross-validated mean and variance of every output at every design: each
    fold predicted by the GPs (``fit``: one per output, or ``fit_vector_gp``) refitted,
    hyperparameters too, without it.
    Designs that share a geometry (the two PDMS bodies of a pooled group at one Sobol
    point) fall in one fold.

    Why not the closed-form leave-one-out: with the hyperparameters fitted to every
    design, and a PDMS twin left in, its bands (calibrated to cover 95 %) covered
    0.72 of the points of 15 held-out random FE designs."""
    geometry = np.round(u[:, :GEOMETRY_COORDINATES], 6)
    _, which = np.unique(geometry, axis=0, return_inverse=True)
    which = np.asarray(which).ravel()
    order = np.random.default_rng(seed).permutation(which.max() + 1)
    fold = (order % folds)[which]
    mean, var = np.empty_like(y), np.empty_like(y)
    for k in range(folds):
        test = fold == k
        if not test.any():
            continue
        gp = fit(u[~test], y[~test], seed=seed)
        mean[test], var[test] = gp.predict_many(u[test])
    return mean, var


def held_out_curves(curves: list, mean: np.ndarray, var: np.ndarray, scales: np.ndarray,
                    z: float, axis: str = "pressure"
                    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Per database curve: its FE angles (deg, up to the FE's stop, signed positive) and
    the held-out (cross-validated) emulator's angle, band lower and upper (with the
    query's floor, ``emulator.floored_band``) at the curve's own pressures (``axis``
    "pressure": the log p nodes) or injected volumes ("volume": the log V nodes), from the
    held-out node means and variances."""
    half = slice(0, N_NODES) if axis == "pressure" else slice(N_NODES, 2 * N_NODES)
    out = []
    for i, (p_red, v_red, a) in enumerate(curves):
        sign = 1.0 if a[np.argmax(np.abs(a))] >= 0 else -1.0
        keep = np.abs(a) <= LIMIT_ANGLE_DEG
        y, sd = mean[i, half], np.sqrt(var[i, half]) * scales[half]
        shape = _monotone if axis == "pressure" else volume_shape
        xm, xl, xu = (_with_origin(shape(c)) for c in node_curves(y, sd, z))
        q = (p_red if axis == "pressure" else v_red)[keep]
        angle = np.interp(q, xm, ANGLES0)
        lower, upper = floored_band(angle, np.interp(q, xu, ANGLES0), np.interp(q, xl, ANGLES0))
        out.append((sign * a[keep], angle, lower, upper))
    return out


def angle_bin(angle_deg: np.ndarray) -> np.ndarray:
    """Index of the ANGLE_BINS_DEG bin of each angle (the last bin closed)."""
    edges = np.asarray(ANGLE_BINS_DEG)
    return np.clip(np.searchsorted(edges, angle_deg, side="right") - 1, 0, len(edges) - 2)


def cv_band_target(level: float) -> float:
    """The cross-validated coverage each angle bin's band multiplier aims at for a
    ``level`` band: 1 - (1 - level) / 5 (0.99 for 95 %; the bisection reaches 0.965-0.98
    overall on the shipped database). The folds leave out Sobol points of the database's
    own reduced box; random designs drawn uniformly in the whole box (each layer's
    stiffness scaled on its own) sit further from the database: bands calibrated to 95 %
    in cross-validation covered 0.92 of 22 held-out FE curves' points, to 97.5 % also
    0.92, to 99 % 0.94 (benchmarks/RESULTS.md)."""
    return 1.0 - (1.0 - level) / 5.0


def node_band_scales(curves: list, mean: np.ndarray, var: np.ndarray, level: float
                     ) -> np.ndarray:
    """The sd multiplier of every output node (log p, then log V, at each angle node).

    ``mean`` and ``var`` are held-out predictions at the database designs
    (``cross_validated``). Pressure nodes: one multiplier per angle bin
    (ANGLE_BINS_DEG), the smallest whose held-out bands cover ``level`` of the FE points
    with angles in that bin
    (bisection, bins from low angles up, two sweeps). One multiplier for the whole curve was set by
    the low-angle points, where the FE steps crowd (half the points lie below 10 deg) and
    the GP's sd is smallest relative to its error: above 10 deg those bands covered every
    held-out point and were +-30 deg wide. Volume nodes: the same, for the band by
    injected volume at the curves' own FE volumes.
    All kept within [MIN_BAND_SCALE, 50]: a band is never narrower than the GP's own
    predictive sd. Cross-validation alone put the multipliers above 10 deg at 0.5-0.8,
    and such bands covered only 0.72 of the points of 15 held-out random FE designs
    (benchmarks/RESULTS.md); at 1.0 those covered 0.97-1.0 above 20 deg."""
    z = z_value(level)
    node_bin = angle_bin(ANGLE_NODES_DEG)
    scales = np.ones(2 * N_NODES)
    for axis, offset in (("pressure", 0), ("volume", N_NODES)):
        fe_bins = [angle_bin(fe) for fe, *_ in
                   held_out_curves(curves, mean, var, scales, z, axis)]
        # two sweeps: a bin's nodes also shape the band just outside it
        for b in list(range(len(ANGLE_BINS_DEG) - 1)) * 2:
            nodes = offset + np.flatnonzero(node_bin == b)
            lo_s, hi_s = MIN_BAND_SCALE, 50.0
            for _ in range(20):
                mid = np.sqrt(lo_s * hi_s)
                scales[nodes] = mid
                held = held_out_curves(curves, mean, var, scales, z, axis)
                if _bin_coverage(held, fe_bins, b) >= level:
                    hi_s = mid
                else:
                    lo_s = mid
            scales[nodes] = hi_s
    return np.clip(scales, MIN_BAND_SCALE, 50.0)


def near_failed_mask(u: np.ndarray, failed: list) -> np.ndarray:
    """Which designs (rows of ``u``, unit cube) lie within NEAR_FAILED_RADIUS of an
    early-ended curve of ``failed`` ((u, end angle, reason) tuples), as a query there
    would be flagged (``near_early_ended_fe_curves``)."""
    points = np.array([np.asarray(f[0], float) for f in failed]) if failed else None
    return nearest_distance(u, points) < NEAR_FAILED_RADIUS


def _coverage(held: list) -> float:
    """Share of all held-out FE points inside their band."""
    return float(np.mean(np.concatenate([(fe >= lo - 1e-9) & (fe <= hi + 1e-9)
                                         for fe, _, lo, hi in held])))


def _bin_coverage(held: list, fe_bins: list, b: int) -> float:
    """Share of the held-out FE points of angle bin ``b`` inside their band."""
    inside = total = 0
    for (fe, _, lo, hi), bins in zip(held, fe_bins):
        sel = bins == b
        inside += int(((fe[sel] >= lo[sel] - 1e-9) & (fe[sel] <= hi[sel] + 1e-9)).sum())
        total += int(sel.sum())
    return inside / total if total else 1.0


def _cv_angle_report(curves: list, mean: np.ndarray, var: np.ndarray,
                      scales: np.ndarray, level: float) -> dict:
    """Cross-validated angle errors (deg) and band coverage, overall and by angle bin:
    each database curve predicted by the emulator fitted without its fold, at the
    curve's own pressures."""
    held = held_out_curves(curves, mean, var, scales, z_value(level))
    errors = [m - fe for fe, m, _, _ in held]
    flat = np.concatenate(errors)
    ins = np.concatenate([(fe >= lo - 1e-9) & (fe <= hi + 1e-9) for fe, _, lo, hi in held])
    bins = angle_bin(np.concatenate([fe for fe, *_ in held]))
    by_bin = []
    for b, (a0, a1) in enumerate(zip(ANGLE_BINS_DEG[:-1], ANGLE_BINS_DEG[1:])):
        sel = bins == b
        if sel.any():
            by_bin.append({"from_deg": a0, "to_deg": a1, "points": int(sel.sum()),
                           "coverage": float(ins[sel].mean()),
                           "rmse_deg": float(np.sqrt(np.mean(flat[sel] ** 2)))})
    return {"cv_rmse_deg": float(np.sqrt(np.mean(flat**2))),
            "cv_max_deg": float(np.max(np.abs(flat))),
            "cv_curve_rmse_deg": [float(np.sqrt(np.mean(e**2))) for e in errors],
            "cv_coverage": float(ins.mean()), "cv_coverage_by_angle": by_bin,
            "cv_coverage_by_volume": _coverage(held_out_curves(curves, mean, var, scales,
                                                               z_value(level), "volume")),
            "band_scale_median": float(np.median(scales[:N_NODES])),
            "band_scale_range": [float(scales.min()), float(scales.max())]}


def _near_failed_report(curves: list, mean: np.ndarray, var: np.ndarray,
                        band_scale: np.ndarray, near: np.ndarray, level: float) -> dict:
    """Cross-validated angle RMSE and band coverage of the curves near an early-ended one
    and of the others, by pressure (the random designs' calibration,
    ``random_calibration``, widens the bands of the near ones)."""
    z = z_value(level)
    out: dict = {"curves": int(near.sum()), "far_curves": int((~near).sum())}
    for name, sel in (("far", ~near), ("near", near)):
        idx = np.flatnonzero(sel)
        if not len(idx):
            continue
        held = held_out_curves([curves[i] for i in idx], mean[idx], var[idx], band_scale, z)
        out[f"{name}_cv_coverage"] = _coverage(held)
        out[f"{name}_cv_rmse_deg"] = float(np.sqrt(np.mean(np.concatenate(
            [(m - fe) ** 2 for fe, m, _, _ in held]))))
    return out


def pushes_with(per_kpa: np.ndarray, sign: float) -> np.ndarray:
    """Which blocked-tip rows (F / p at the force nodes, NaN past the curve's end) push the
    way a sub-emulator of bending ``sign`` bends, judged at each row's last node: a group's
    blocked-tip designs are collected for the group, and Ecoflex on Ecoflex bends either
    way (until 2026-12-04 each sign's force model was fitted to both signs' designs, and
    one reversed-pair design pushing the other way set five of its node GPs' length scales
    to 0.1-0.2)."""
    y = np.asarray(per_kpa, float)
    reached = np.isfinite(y).sum(axis=1)
    last = y[np.arange(len(y)), np.maximum(reached - 1, 0)]
    return (reached > 0) & (sign * last > 0)


def force_angle_rows(u: np.ndarray, per_kpa: np.ndarray, curves: CurveGPs, sign: float
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The rows an "angle_ratio" force model of bending ``sign`` is fitted to: of the
    group's blocked-tip rows (designs ``u``, F / p at the force nodes from ``_collect``;
    mN/kPa, reduced), those that push its way (``pushes_with``), and their force variable
    (``features.force_angle_feature``): F over the group's emulated free-tip angle at the
    same pressure (the complete-curve GPs ``curves``, without the early-ended curves'
    blend, as a query's force reads them: ``CurveBand.force_reference``; the force designs
    are few, the free curves many). NaN where the free curve has ended (past 90 deg)."""
    same = pushes_with(per_kpa, sign)
    u, per_kpa = u[same], per_kpa[same]
    means = curves.predict_many(u, variance_of=MEANS_ONLY)[0]
    angle = sign * free_angles_deg(means, FORCE_PRESSURE_NODES_PA)
    return u, force_angle_feature(per_kpa * FORCE_PRESSURE_NODES_PA / 1000.0, angle)


def force_range(u: np.ndarray, y: np.ndarray, share: float = FORCE_SHARE
                ) -> tuple[int, np.ndarray, np.ndarray]:
    """The force nodes a group's emulator covers, and the curves it is fitted to: the most
    nodes (from the lowest pressure) that at least ``share`` of the group's blocked-tip
    curves, and MIN_DESIGNS of them, reach (a soft pair's FE curves stop early at the
    volume stop, so its force range ends lower); 0 nodes when none qualify."""
    reach = np.isfinite(y).cumprod(axis=1).sum(axis=1)       # nodes reached, per curve
    for k in range(y.shape[1], 0, -1):
        ok = reach >= k
        if ok.sum() >= max(MIN_DESIGNS, share * len(y)):
            return k, u[ok], y[ok, :k]
    return 0, u[:0], y[:0, :0]


def force_band_scale(u: np.ndarray, y: np.ndarray, level: float, seed: int = 0,
                     end_pa: np.ndarray | None = None) -> tuple[float, tuple[float, ...]]:
    """The force band's sd multiplier, and its further multipliers near the end of a
    design's blocked-tip curve: from the cross-validated |error| / sd of the force
    variable (each fold's GPs refitted without it, ``force_gps.fit_force_nodewise``) at
    every node each design ``u`` reaches (``y``: NaN past its end). The multiplier is the
    ``level`` quantile over all of them, over the level's z, never below MIN_BAND_SCALE;
    near the end (``end_pa``: each design's blocked-tip end as the blocked range emulates
    it without that design, reduced Pa; None: not known) each bin of node pressure / end
    from ``blocked_range.NEAR_END_FROM`` on gets the quantile of its own points over the
    overall one (``blocked_range.near_end_band_scales``).

    Why not the closed-form leave-one-out (until 2026-12-02, eighth session): with the
    hyperparameters fitted to every design it put the multiplier below 1 in every group
    (held at 1), and those bands covered 0.80 of the points of four held-out random
    blocked-tip FE curves. Cross-validated, |error| / sd has a median near 1 but a heavy
    tail (its 95th percentile 3.5-5.8 with 16-24 blocked-tip designs per group): the
    multipliers are 1.8-2.9, and the bands covered 0.99 of those points. Why not the
    curves' stricter target (``cv_band_target``): with a tail this heavy its 99th
    percentile (multipliers 2.2-5.5) withheld half the held-out force points as too
    uncertain while covering them all."""
    n = len(u)
    try:
        # a fold of 5 leaves too few designs for a GP in 6 inputs below 2 x MIN_DESIGNS:
        # then one design (or PDMS twin pair) at a time
        fm, fv = cross_validated(u, y, seed, folds=CV_FOLDS if n >= 2 * MIN_DESIGNS else n,
                                 fit=fit_force_nodewise)
    except ValueError:          # still too few to refit: the closed form, hyperparameters kept
        complete = nodes_reached(y) >= y.shape[1]
        fm, fv = np.full(y.shape, np.nan), np.full(y.shape, np.nan)
        fm[complete], fv[complete] = fit_force_gps(u[complete], y[complete], seed=seed).loo()
    zs = np.abs(fm - y) / np.sqrt(np.maximum(fv, 1e-300))
    ok = np.isfinite(zs)
    scale = float(max(np.quantile(zs[ok], level) / z_value(level), MIN_BAND_SCALE))
    near = (1.0,) * len(NEAR_END_FROM)
    if end_pa is not None:
        share = FORCE_PRESSURE_NODES_PA[None, :y.shape[1]] / np.asarray(end_pa)[:, None]
        near = near_end_band_scales(zs[ok] / (z_value(level) * scale), share[ok], level)
    return scale, near


def _fit_one(key: str, rows: _Rows, keep: np.ndarray, sign: float, level: float, seed: int,
             force_rows: tuple[list, list] | None, range_model: VectorGP | None = None,
             blocked_range: BlockedRange | None = None,
             stretch_hazard: StretchHazard | None = None) -> tuple[PairEmulator, dict]:
    u = np.array(rows.u)[keep]
    y = np.array(rows.y)[keep]
    curves = [c for c, k in zip(rows.curves, keep) if k]
    keys = tuple(k for k, kk in zip(rows.keys, keep) if kk)
    # the early-ended curves of this sign that reach the first node
    early = [i for i, s in enumerate(rows.failed_signs)
             if s == sign and np.isfinite(rows.failed_y[i][0])]
    early_u = np.array([rows.failed[i][0] for i in early]).reshape(-1, u.shape[1])
    early_y = np.array([rows.failed_y[i] for i in early]).reshape(-1, y.shape[1])
    early_step = np.array([rows.failed_last_step[i] for i in early])
    vgp = fit_curve_gps(u, y, seed=seed, early_u=early_u, early_y=early_y,
                        early_last_step_deg=early_step)
    cv_mean, cv_var = cross_validated(u, y, seed)
    band_scale = node_band_scales(curves, cv_mean, cv_var, cv_band_target(level))
    near = near_failed_mask(u, rows.failed)
    cv = _cv_angle_report(curves, cv_mean, cv_var, band_scale, level)
    cv["near_failed"] = _near_failed_report(curves, cv_mean, cv_var, band_scale, near, level)
    force_gp, force_scale, force_nodes, force_designs = None, 1.0, 0, 0
    if force_rows is not None:
        au, ay = force_angle_rows(np.array(force_rows[0]), np.array(force_rows[1]), vgp,
                                  sign)
        force_nodes, fu, fy = force_range(au, ay)
        force_designs = len(fu)
    if force_designs >= MIN_DESIGNS:
        # every design that reaches the first node, each node conditioned on those that
        # reach it (force_gps.py)
        reach = nodes_reached(ay[:, :force_nodes]) > 0
        au, ay = au[reach], ay[reach, :force_nodes]
        force_gp = fit_force_nodewise(au, ay, seed=seed)
        ends = None if blocked_range is None else blocked_range.left_out_ends_pa(au)
        force_scale, near_end = force_band_scale(au, ay, level, seed, ends)
        if blocked_range is not None:
            blocked_range = replace(blocked_range, near_end_band_scale=near_end)
    force_limit_pa = float(FORCE_PRESSURE_NODES_PA[max(force_nodes, 1) - 1])
    failed = tuple((np.array(fu), fa, fr) for fu, fa, fr in rows.failed)
    pe = PairEmulator(
        pair=key, sign=sign, curves=vgp, band_scale=band_scale,
        fe_limit_angle_deg=LIMIT_ANGLE_DEG,
        fe_stop_reason=f"the default FE curves stop at {LIMIT_ANGLE_DEG:g} deg "
                       "(SolverSettings.max_angle_deg)",
        fe_max_volume_ul=default_free_settings().max_volume_ul,
        coordinates=u, keys=keys, force=force_gp, force_band_scale=force_scale,
        force_limit_pa=force_limit_pa, failed=failed, force_form=FORCE_FORMS[2],
        range_model=range_model,
        blocked_range=blocked_range if force_gp is not None else None,
        failed_end_volume_ul=np.array(rows.failed_end_volume, float),
        stretch_hazard=stretch_hazard)
    report = {"designs": int(keep.sum()), "failed_designs": len(failed),
              "components": len(vgp.gp.gps),
              "force_designs": force_designs if force_gp is not None else 0,
              "force_designs_by_node": ([int(len(g.y)) for g in force_gp.gps]
                                        if force_gp is not None else []),
              "force_band_scale": force_scale,
              "force_limit_pa": force_limit_pa if force_gp is not None else None,
              "blocked_tip_ended_early": (len(blocked_range.ended) if force_gp is not None
                                          and blocked_range is not None else 0),
              "force_near_end_band_scale": (list(blocked_range.near_end_band_scale)
                                            if force_gp is not None
                                            and blocked_range is not None else None),
              "stretch_hazard": (None if stretch_hazard is None else
                                 {"reached": stretch_hazard.reached,
                                  "failed": stretch_hazard.failed}),
              "fitted": True, **cv}
    return pe, report


def fit_emulator(records: Iterable, name: str = "emulator", level: float = 0.95,
                 provenance: dict | None = None, seed: int = 0) -> Emulator:
    """One emulator per material group (``solver.design_space.GROUPS``) and bending sign
    with at least MIN_DESIGNS complete curves; where a group bends both ways (a soft body
    on a soft membrane), a GP of the sign over the box says which applies."""
    free, force, blocked_ends = _collect(records)
    models: dict[str, PairEmulator] = {}
    sign_models: dict[str, object] = {}
    balance_models: dict[str, BalanceModel] = {}
    report: dict[str, object] = {"level": level, "pairs": {}, "balance": {}}
    for group in sorted(set(GROUPS.values())):
        rows = free.get(group)
        if rows is None or len(rows.u) < MIN_DESIGNS:
            report["pairs"][group] = {  # type: ignore[index]
                "designs": 0 if rows is None else len(rows.u), "fitted": False}
            continue
        signs = np.array(rows.signs)
        all_u = np.array(rows.u + [np.asarray(f[0]) for f in rows.failed])
        all_signs = np.concatenate((signs, np.array(rows.failed_signs)))
        both = (all_signs > 0).any() and (all_signs < 0).any()
        if both:
            sign_models[group] = fit_vector_gp(all_u, all_signs[:, None], seed=seed)
            # where the sign model cannot tell the direction: the signed angle by volume
            balance, report["balance"][group] = fit_balance_model(  # type: ignore[index]
                np.array([r[0] for r in rows.by_volume]), [r[1] for r in rows.by_volume],
                seed=seed)
            if balance is not None:
                balance_models[group] = balance
        range_model = None
        if rows.failed:
            # where each curve of the group ends, over the box (emulator.RANGE_Z)
            ends = np.concatenate((np.full(len(rows.u), LIMIT_ANGLE_DEG),
                                   [a for _, a, _ in rows.failed])) / 90.0
            range_model = fit_vector_gp(all_u, ends[:, None], seed=seed)
        # where each blocked-tip curve of the group ends (the force's range)
        blocked_range = (fit_blocked_range(*blocked_ends[group], seed=seed)
                         if group in blocked_ends else None)
        # the group's emulated membrane stretch, and how often its FE curves failed past
        # the hazard stretch (stretch_hazard.py)
        hazard = np.array(rows.hazard, bool).reshape(-1, 2)
        stretch_hazard = fit_stretch_hazard(
            np.array(rows.u), np.array(rows.stretch), reached=int(hazard[:, 0].sum()),
            failed=int((hazard[:, 0] & hazard[:, 1]).sum()),
            min_designs=MIN_DESIGNS, seed=seed)
        for sign in (1.0, -1.0):
            keep = signs == sign
            key = group + ("+" if sign > 0 else "-")
            if keep.sum() < MIN_DESIGNS:
                if keep.any():
                    report["pairs"][key] = {"designs": int(keep.sum()),  # type: ignore
                                            "fitted": False}
                continue
            pe, rep = _fit_one(key, rows, keep, sign, level, seed, force.get(group),
                               range_model, blocked_range, stretch_hazard)
            models[key] = pe
            report["pairs"][key] = rep  # type: ignore[index]
    if not models:
        raise InputError("db", "no material pair has enough default-FE curves in the box",
                         f">= {MIN_DESIGNS} complete free-tip curves per pair")
    nodes, report["variance_nodes"] = choose_variance_nodes(models.values())
    return Emulator(name=name, pairs=models, provenance=dict(provenance or {}), report=report,
                    sign_models=sign_models, variance_nodes=nodes,  # type: ignore[arg-type]
                    balance_models=balance_models)
