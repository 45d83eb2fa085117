"""Fit the emulator from the curve database: one sub-emulator per material group and
bending sign, with its bands and its accuracy report.

    emulator = fit_emulator(records)          # records: iterable of solver.store.Record

The records as rows by group (which count, reduced to the box's terms):
``database_rows``. Per group and sign with at least MIN_DESIGNS complete curves: the
curve GPs (``fit_curve_gps``), the bands' sd multipliers calibrated on cross-validated
curves (``band_scales``: they cover ``level`` of the held-out FE points in every angle
bin), the accuracy report (``accuracy_report``), and from the blocked-tip curves the force
model (``force_fit``). Curves that end before 90 deg (the FE failed or stopped) are not
interpolated; they limit the range of every query within ``FAILED_RADIUS`` of them
(unit-cube distance), through a GP of the end angle over the box. Every query's range
also ends where its emulated injected volume reaches the FE's volume stop
(``SolverSettings.max_volume_ul``), as the FE's own curve would.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace

import numpy as np

from solver.design_space import GROUPS
from solver.errors import InputError
from surrogate.emulator.accuracy_report import (
    cv_angle_report,
    near_failed_mask,
    near_failed_report,
)
from surrogate.emulator.balance import BalanceModel, fit_balance_model
from surrogate.emulator.band_scales import cross_validated, cv_band_target, node_band_scales
from surrogate.emulator.blocked_range import BlockedRange, fit_blocked_range
from surrogate.emulator.curve_gps import CurveGPs, anchor_index, rise_outputs
from surrogate.emulator.database_rows import (
    LIMIT_ANGLE_DEG,
    MIN_DESIGNS,
    GroupRows,
    collect_rows,
    default_free_settings,
)
from surrogate.emulator.early_ended_nodes import EarlyEndedRows, short_of_the_end
from surrogate.emulator.emulator import Emulator
from surrogate.emulator.features import FORCE_PRESSURE_NODES_PA, N_NODES
from surrogate.emulator.force_fit import force_angle_rows, force_band_scale, force_range
from surrogate.emulator.force_gps import fit_force_nodewise, nodes_reached
from surrogate.emulator.pair_emulator import FORCE_FORMS, PairEmulator
from surrogate.emulator.shape_gps import (
    TOP_PRESSURE_FROM,
    TOP_PRESSURE_MIN_DESIGNS,
    TOP_SHAPE_NODES_DEG,
    VOLUME_SHAPE_NODES_DEG,
    fit_shape_gps,
)
from surrogate.emulator.stretch_hazard import StretchHazard, fit_stretch_hazard
from surrogate.emulator.variance_nodes import choose as choose_variance_nodes
from surrogate.emulator.vector_gp import VectorGP, fit_output_gps, fit_vector_gp


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


def _fit_one(key: str, rows: GroupRows, keep: np.ndarray, sign: float, level: float, seed: int,
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
    cv_mean, cv_var = cross_validated(u, y, seed, fit=fit_curve_gps)
    band_scale = node_band_scales(curves, cv_mean, cv_var, cv_band_target(level))
    near = near_failed_mask(u, rows.failed)
    cv = cv_angle_report(curves, cv_mean, cv_var, band_scale, level)
    cv["near_failed"] = near_failed_report(curves, cv_mean, cv_var, band_scale, near, level)
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
    free, force, blocked_ends = collect_rows(records)
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
