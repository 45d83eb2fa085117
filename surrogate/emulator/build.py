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

Bands: the GP's standard deviation times ``band_scale``, chosen so that leave-one-out
(LOO) bands cover ``level`` of the LOO FE points in angle (each database curve
predicted by the emulator fitted without it, read at the curve's own pressures).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from solver.design_space import GROUPS, locate
from solver.errors import InputError
from solver.settings import SolverSettings
from surrogate.band_level import z_value
from surrogate.emulator.emulator import (
    _B_ANGLE,
    ANGLES0,
    N_NODES,
    Emulator,
    PairEmulator,
    _monotone,
    _with_origin,
)
from surrogate.emulator.features import (
    FINE_ANGLES_DEG,
    FORCE_PRESSURE_NODES_PA,
    curve_features,
    force_features,
)
from surrogate.emulator.vector_gp import fit_vector_gp

LIMIT_ANGLE_DEG = 90.0            # the default FE's stop (SolverSettings.max_angle_deg)
FAILED_RADIUS = 0.15
MIN_DESIGNS = 10
FORCE_SHARE = 0.6                 # of a group's blocked-tip curves its force range keeps


@dataclass
class _Rows:
    u: list
    y: list
    keys: list
    curves: list          # (p_red, angle) per record, for LOO in angle
    failed: list          # (u, end angle, reason)
    signs: list
    failed_signs: list


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


def _collect(records: Iterable) -> tuple[dict, dict]:
    free_settings = default_free_settings()
    free: dict[tuple[str, str], _Rows] = {}
    force: dict = {}
    for rec in records:
        try:
            point = locate(rec.design, reduced=True)
        except InputError:
            continue
        c = rec.curve
        if rec.settings == free_settings:
            rows = free.setdefault(point.group, _Rows([], [], [], [], [], [], []))
            f = curve_features(c.pressure_pa / point.pressure_scale,
                               c.volume_ul / point.length_scale**3, c.angle_deg)
            u = point.coordinates()
            if f.end_angle_deg < LIMIT_ANGLE_DEG or not np.isfinite(f.log_p).all():
                rows.failed.append((u.tolist(), min(f.end_angle_deg, LIMIT_ANGLE_DEG),
                                    c.reason))
                rows.failed_signs.append(f.sign)
                continue
            rows.u.append(u)
            rows.y.append(np.concatenate((f.log_p, f.log_v)))
            rows.keys.append(rec.key)
            rows.curves.append((c.pressure_pa / point.pressure_scale, c.angle_deg))
            rows.signs.append(f.sign)
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
    force = {g: ([np.array(k) for k in rows_f], list(rows_f.values()))
             for g, rows_f in force.items()}
    return free, force


def _band_scale_for(curves: list, mean: np.ndarray, var: np.ndarray, level: float
                    ) -> tuple[float, dict]:
    """The sd multiplier whose LOO bands cover ``level`` of the LOO FE points, and the LOO
    angle errors (deg) at scale 1."""
    z = z_value(level)
    theta = FINE_ANGLES_DEG

    def angles(i: int, shift: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        p_red, a = curves[i]
        sign = 1.0 if a[np.argmax(np.abs(a))] >= 0 else -1.0
        keep = np.abs(a) <= LIMIT_ANGLE_DEG
        y, sd = mean[i, :N_NODES], np.sqrt(var[i, :N_NODES])
        pm = _with_origin(_monotone(theta * np.exp(_B_ANGLE @ y)))
        pl = _with_origin(_monotone(theta * np.exp(_B_ANGLE @ (y - shift * sd))))
        pu = _with_origin(_monotone(theta * np.exp(_B_ANGLE @ (y + shift * sd))))
        q = p_red[keep]
        return (sign * a[keep], np.interp(q, pm, ANGLES0), np.interp(q, pu, ANGLES0),
                np.interp(q, pl, ANGLES0))

    errors = []
    for i in range(len(curves)):
        fe, m, _, _ = angles(i, 0.0)
        errors.append(m - fe)
    flat = np.concatenate(errors)

    def coverage(scale: float) -> float:
        inside = total = 0
        for i in range(len(curves)):
            fe, _, lo, hi = angles(i, scale * z)
            inside += int(((fe >= lo - 1e-9) & (fe <= hi + 1e-9)).sum())
            total += len(fe)
        return inside / max(total, 1)

    lo_s, hi_s = 0.2, 20.0
    if coverage(hi_s) < level:
        scale = hi_s
    else:
        for _ in range(30):
            mid = np.sqrt(lo_s * hi_s)
            if coverage(mid) >= level:
                hi_s = mid
            else:
                lo_s = mid
        scale = hi_s
    per_curve = [float(np.sqrt(np.mean(e**2))) for e in errors]
    report = {"loo_rmse_deg": float(np.sqrt(np.mean(flat**2))),
              "loo_max_deg": float(np.max(np.abs(flat))),
              "loo_curve_rmse_deg": per_curve,
              "loo_coverage_at_scale_1": coverage(1.0), "band_scale": float(scale),
              "loo_coverage": coverage(scale)}
    return float(scale), report


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


def _fit_one(key: str, rows: _Rows, keep: np.ndarray, sign: float, level: float, seed: int,
             force_rows: tuple[list, list] | None) -> tuple[PairEmulator, dict]:
    u = np.array(rows.u)[keep]
    y = np.array(rows.y)[keep]
    curves = [c for c, k in zip(rows.curves, keep) if k]
    keys = tuple(k for k, kk in zip(rows.keys, keep) if kk)
    vgp = fit_vector_gp(u, y, seed=seed)
    loo_mean, loo_var = vgp.loo()
    band_scale, loo = _band_scale_for(curves, loo_mean, loo_var, level)
    force_gp, force_scale, force_nodes, force_designs = None, 1.0, 0, 0
    if force_rows is not None:
        force_nodes, fu, fy = force_range(np.array(force_rows[0]), np.array(force_rows[1]))
        force_designs = len(fu)
    if force_designs >= MIN_DESIGNS:
        force_gp = fit_vector_gp(fu, fy, seed=seed)
        fm, fv = force_gp.loo()
        zs = np.abs(fm - fy) / np.sqrt(fv)
        force_scale = float(max(np.quantile(zs, level) / z_value(level), 0.5))
    force_limit_pa = float(FORCE_PRESSURE_NODES_PA[max(force_nodes, 1) - 1])
    failed = tuple((np.array(fu), fa, fr) for fu, fa, fr in rows.failed)
    pe = PairEmulator(
        pair=key, sign=sign, curves=vgp, band_scale=band_scale,
        fe_limit_angle_deg=LIMIT_ANGLE_DEG,
        fe_stop_reason=f"the default FE curves stop at {LIMIT_ANGLE_DEG:g} deg "
                       "(SolverSettings.max_angle_deg)",
        coordinates=u, keys=keys, force=force_gp, force_band_scale=force_scale,
        force_limit_pa=force_limit_pa, failed=failed)
    report = {"designs": int(keep.sum()), "failed_designs": len(failed),
              "components": len(vgp.gps),
              "force_designs": force_designs if force_gp is not None else 0,
              "force_band_scale": force_scale,
              "force_limit_pa": force_limit_pa if force_gp is not None else None,
              "fitted": True, **loo}
    return pe, report


def fit_emulator(records: Iterable, name: str = "emulator", level: float = 0.95,
                 provenance: dict | None = None, seed: int = 0) -> Emulator:
    """One emulator per material group (``solver.design_space.GROUPS``) and bending sign
    with at least MIN_DESIGNS complete curves; where a group bends both ways (a soft body
    on a soft membrane), a GP of the sign over the box says which applies."""
    free, force = _collect(records)
    models: dict[str, PairEmulator] = {}
    sign_models: dict[str, object] = {}
    report: dict[str, object] = {"level": level, "pairs": {}}
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
        for sign in (1.0, -1.0):
            keep = signs == sign
            key = group + ("+" if sign > 0 else "-")
            if keep.sum() < MIN_DESIGNS:
                if keep.any():
                    report["pairs"][key] = {"designs": int(keep.sum()),  # type: ignore
                                            "fitted": False}
                continue
            pe, rep = _fit_one(key, rows, keep, sign, level, seed, force.get(group))
            models[key] = pe
            report["pairs"][key] = rep  # type: ignore[index]
    if not models:
        raise InputError("db", "no material pair has enough default-FE curves in the box",
                         f">= {MIN_DESIGNS} complete free-tip curves per pair")
    return Emulator(name=name, pairs=models, provenance=dict(provenance or {}), report=report,
                    sign_models=sign_models)  # type: ignore[arg-type]
