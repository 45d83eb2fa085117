"""Fit a surrogate from FE curves: ``fit_surrogate(curves_or_db_path) -> Surrogate``.

For every family (material pair, T, b, h) with free-tip curves: the paper's procedure
(``surrogate.exponential.paper_procedure``), joint fits of each model form,
leave-one-design-out errors and band coverage per form, a residual profile (how the FE
curves leave the exponential form as the angle grows), the fitted domain, and a force
model when curves with force exist.
The family's default form is "extended" only when it lowers the leave-one-design-out
RMSE by at least 10 % (else the paper's "exponential"). Everything lands in
``Surrogate.report`` (plain JSON).
"""

from __future__ import annotations

import math
import os
from dataclasses import replace
from datetime import UTC, datetime
from typing import Any, cast

import numpy as np

from solver.errors import InputError
from solver.store.record import git_commit, package_version
from surrogate.dataset import CurveData, curves_from_store, select_angle_curves, select_force_curves
from surrogate.exponential import equations
from surrogate.exponential.family import Domain, Family
from surrogate.exponential.family_fit import Points, joint_fit, leave_one_design_out, make_points
from surrogate.exponential.file import FORMAT_VERSION
from surrogate.exponential.paper_procedure import paper_procedure
from surrogate.exponential.parameters import ModelParameters
from surrogate.exponential.surrogate import Surrogate
from surrogate.exponential.volume_relation import VolumeCurve, fit_volume_relation
from surrogate.fit_provenance import database_entry
from surrogate.json_plain import plain_json

EXTENDED_GAIN = 0.9  # extended becomes the default when its LODO RMSE < 0.9 x the paper's
# A family's constants need designs that tell them apart: tau = a_t log10(b_t t) two
# membrane thicknesses, A = a L (and its leave-one-design-out test) two chamber lengths.
# The design-space database's random designs are families of one design each (their own
# T, b, h and stiffness scales): the emulator answers those, not an exponential.
MIN_THICKNESSES = 2
MIN_LENGTHS = 2


def fit_surrogate(source: str | os.PathLike | list[CurveData], *, name: str = "fe-fit",
                  level: float = 0.95, forms: tuple[str, ...] = equations.FORMS,
                  progress: bool = False, command: str = "") -> Surrogate:
    """Fit every family found in ``source`` (a CurveStore path or a list of CurveData);
    ``command`` (the fit's command line) goes into the provenance, with the database's
    name and checksum (``surrogate.fit_provenance``; never its path on this machine)."""
    database: dict[str, object] = {}
    if isinstance(source, (str, os.PathLike)):
        curves, metadata = curves_from_store(source)
        database = database_entry(source, len(curves))
    else:
        curves, metadata = list(source), {}
    for f in forms:
        if f not in equations.FORMS:
            raise InputError("forms", f"unknown form {f!r}", " | ".join(equations.FORMS))
    angle_curves = select_angle_curves(curves)
    if not angle_curves:
        raise InputError("db", "no free-tip curve with at least 3 converged points to fit",
                         "a curve database filled by `balloon precompute`")
    groups: dict[tuple, list[CurveData]] = {}
    for c in angle_curves:
        groups.setdefault(_group_key(c), []).append(c)
    skipped = {k: g for k, g in groups.items() if not _determined(g)}
    groups = {k: g for k, g in groups.items() if k not in skipped}
    if not groups:
        raise InputError("db", f"no family with free-tip curves at {MIN_THICKNESSES} or more "
                         f"membrane thicknesses and {MIN_LENGTHS} or more chamber lengths "
                         f"({len(skipped)} families fall short): the exponential model's "
                         "constants are not determined",
                         "a database with a grid of L and t per family (grids/default.toml)")
    force_groups: dict[tuple, list[CurveData]] = {}
    for c in select_force_curves(curves):
        force_groups.setdefault(_group_key(c), []).append(c)

    families, reports = [], []
    items = sorted(groups.items(), key=lambda kv: str(kv[0]))
    bar = _progress(len(items), progress)
    for key, members in items:
        fam, rep = _fit_family(members, force_groups.get(key, []), forms, level)
        families.append(fam)
        reports.append(rep)
        bar.update(1)
    bar.close()
    used = sorted(c.key for g in groups.values() for c in g) + sorted(
        c.key for key, group in force_groups.items() if key in groups for c in group)
    provenance = {
        "format_version": FORMAT_VERSION, "created_utc": datetime.now(UTC).isoformat(),
        "package_version": package_version(), "git_commit": git_commit(),
        "database_name": database.get("name", ""), "database": database,
        "fit_command": command, "database_metadata": plain_json(metadata),
        "record_keys": used, "n_records": len(used), "level": level, "forms": list(forms),
        "source": "fit of FE curves",
    }
    n_force = sum(key in groups for key in force_groups)
    report = {"level": level, "families": reports,
              "force": "no record holds a force curve" if not n_force else
              f"force models for {n_force} famil(ies)",
              "skipped_families": {
                  "count": len(skipped),
                  "curves": sum(len(g) for g in skipped.values()),
                  "why": f"fewer than {MIN_THICKNESSES} membrane thicknesses or "
                         f"{MIN_LENGTHS} chamber lengths: the constants are not determined "
                         "(the design-space emulator answers these designs)"}}
    return Surrogate(name=name, family_fits=tuple(families), provenance=provenance,
                     report=plain_json(report))


def _determined(members: list[CurveData]) -> bool:
    """Whether a family's curves span enough thicknesses and lengths for its constants."""
    t = {round(c.design.t_mm, 6) for c in members}
    L = {round(c.design.L_mm, 6) for c in members}
    return len(t) >= MIN_THICKNESSES and len(L) >= MIN_LENGTHS


def _group_key(c: CurveData) -> tuple:
    d = c.design
    return (d.family, d.body_material, d.membrane_material)


def _fit_family(members: list[CurveData], force_members: list[CurveData],
                forms: tuple[str, ...], level: float) -> tuple[Family, dict]:
    d0 = members[0].design
    members = sorted(members, key=lambda c: (c.design.L_mm, c.design.t_mm))
    pts = make_points([(c.design.L_mm, c.design.t_mm, *c.usable_points()) for c in members])
    params: dict[str, ModelParameters] = {}
    lodo: dict[str, dict[str, Any]] = {}
    start = None
    for form in forms:
        params[form] = joint_fit(pts, form, start=start)
        if form == "exponential":
            start = params[form].theta
        lodo[form] = leave_one_design_out(pts, form, level, start=params[form].theta)
        if lodo[form].get("available"):
            params[form] = replace(params[form], band_scale=float(lodo[form]["band_scale"]))
    default = "exponential" if "exponential" in forms else forms[0]
    if ("extended" in params and "exponential" in params and lodo["extended"].get("available")
            and lodo["extended"]["rmse"] < EXTENDED_GAIN * lodo["exponential"]["rmse"]):
        default = "extended"
    force, force_report = None, None
    if force_members:
        fpts = make_points([(c.design.L_mm, c.design.t_mm, *c.usable_points("force_mn"))
                            for c in force_members])
        force = joint_fit(fpts, "exponential")
        force_lodo = leave_one_design_out(fpts, "exponential", level, start=force.theta)
        if force_lodo.get("available"):
            force = replace(force, band_scale=float(cast(float, force_lodo["band_scale"])))
        force_report = {"parameters": force.as_dict(), "tip": force_members[0].tip,
                        "spring_k_n_per_m": force_members[0].spring_k_n_per_m,
                        "lodo": force_lodo}
    last_p = [float(c.usable_points()[0].max()) for c in members]
    domain = Domain(
        L_mm=(float(pts.L_mm.min()), float(pts.L_mm.max())),
        t_mm=(float(pts.t_mm.min()), float(pts.t_mm.max())),
        pressure_max_pa=max(last_p), angle_max_deg=float(np.abs(pts.value).max()),
        W_mm=tuple(sorted({round(c.design.W_mm, 6) for c in members})),
        designs=tuple((c.design.L_mm, c.design.t_mm) for c in members))
    volume = fit_volume_relation(_volume_curves(members), level)
    fam = Family(body_material=d0.body_material, membrane_material=d0.membrane_material,
                 T_mm=d0.T_mm, b_mm=d0.b_mm, h_mm=d0.h_mm, parameters=params,
                 default_form=default, domain=domain, force=force, volume=volume)
    report = {"family": fam.label, "key": list(fam.key), "n_curves": len(members),
              "n_points": int(len(pts.value)), "record_keys": [c.key for c in members],
              "default_form": default, "domain": domain.as_dict(),
              "paper_procedure": paper_procedure(pts),
              "joint_fit": {f: p.as_dict() for f, p in params.items()},
              "lodo": lodo, "residual_profile": residual_profile(pts, params),
              "force": force_report,
              "volume": None if volume is None else {"lodo": volume.lodo,
                                                     "angle_max_deg": volume.angle_max_deg}}
    return fam, report


def _volume_curves(members: list[CurveData]) -> list[VolumeCurve]:
    """The curves with an injected-volume column, one per (L, t), at the family's most
    common actuator width W (the relation is over L and t only)."""
    with_v = [c for c in members if c.volume_ul is not None]
    if not with_v:
        return []
    widths = [round(c.design.W_mm, 6) for c in with_v]
    w = max(set(widths), key=widths.count)
    out: dict[tuple[float, float], VolumeCurve] = {}
    for c, cw in zip(with_v, widths, strict=True):
        key = (round(c.design.L_mm, 6), round(c.design.t_mm, 6))
        if cw == w and key not in out and c.volume_ul is not None:
            out[key] = VolumeCurve(c.design.L_mm, c.design.t_mm, c.angle_deg, c.volume_ul)
    return list(out.values())


def residual_profile(pts: Points, params: dict) -> dict[str, object]:
    """Mean and RMS of (FE - model) per band of |FE angle| for each form: a systematic,
    growing mean at large angles is the FE curve leaving the exponential form."""
    edges = [0.0, 5.0, 15.0, 30.0, 60.0, 90.0, math.inf]
    sign = np.sign(np.sum(pts.value)) or 1.0
    out: dict[str, object] = {"angle_bands_deg": edges[:-1] + ["inf"],
                              "note": "residual = sign * (FE - model), sign of the family"}
    for form, par in params.items():
        r = sign * (pts.value - equations.angle_deg(par.theta, pts.L_mm, pts.t_mm, pts.pressure_pa))
        mag = np.abs(pts.value)
        rows = []
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            sel = (mag >= lo) & (mag < hi)
            rows.append({"from_deg": lo, "to_deg": None if math.isinf(hi) else hi,
                         "n": int(sel.sum()),
                         "mean": float(r[sel].mean()) if sel.any() else None,
                         "rms": float(np.sqrt(np.mean(r[sel] ** 2))) if sel.any() else None})
        out[form] = rows
    return out


class _NoBar:
    def update(self, n: int) -> None:
        pass

    def close(self) -> None:
        pass


def _progress(total: int, show: bool) -> Any:
    if not show:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, desc="fitting families", unit="family")


def attach_volume_relations(s: Surrogate, curves: list[CurveData], level: float = 0.95,
                            note: str = "") -> Surrogate:
    """``s`` with each family's pressure-volume relation fitted from those of ``curves``
    (free tip) whose record keys ``s`` was fitted from; its parameters unchanged. For a
    file fitted before format version 3 (``python -m surrogate.exponential.add_volumes``)."""
    keys = set(s.provenance.get("record_keys", ()))
    groups: dict[tuple, list[CurveData]] = {}
    for c in select_angle_curves([c for c in curves if c.key in keys]):
        groups.setdefault(c.design.family, []).append(c)
    families, reports = [], []
    for fam, rep in zip(s.family_fits, s.report.get("families", [{}] * len(s.family_fits)),
                        strict=True):
        members = [c for c in groups.get(fam.key, []) if fam.matches(c.design)]
        volume = fit_volume_relation(_volume_curves(members), level)
        families.append(replace(fam, volume=volume))
        reports.append({**rep, "volume": None if volume is None else {
            "lodo": volume.lodo, "angle_max_deg": volume.angle_max_deg}})
    provenance = {**s.provenance, "format_version": FORMAT_VERSION,
                  "volume_relation": {"added_utc": datetime.now(UTC).isoformat(),
                                      "git_commit": git_commit(), "note": note}}
    return replace(s, family_fits=tuple(families), provenance=provenance,
                   report=plain_json({**s.report, "families": reports}))
