"""Curves as the fit sees them, and the thin reader that takes them from a CurveStore.

The fit's core takes plain ``CurveData``: a design and its converged (pressure, angle,
force) points. ``usable_points`` keeps the rising branch only: from the first point
with p > 0 up to the pressure maximum (under volume control the pressure can fall
after a limit point, where angle is no longer a function of pressure).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from solver.design import Design
from solver.settings import MESH_DIVISIONS


@dataclass(frozen=True)
class CurveData:
    """One FE curve: converged points, pressure_pa (Pa), angle_deg (deg), force_mn (mN,
    NaN for a free tip), volume_ul (injected volume, ul; None when not known). ``tip``
    is the solver's tip condition ("free", "spring", "blocked"); only free-tip curves
    inform the angle model, only curves with finite force inform the force model."""

    design: Design
    pressure_pa: np.ndarray
    angle_deg: np.ndarray
    force_mn: np.ndarray | None = None
    key: str = ""
    tip: str = "free"
    spring_k_n_per_m: float = 0.0
    mesh_rank: tuple = field(default=(0, 0, 0))  # finer solves win when a design repeats
    volume_ul: np.ndarray | None = None

    def usable_points(self, quantity: str = "angle_deg") -> tuple[np.ndarray, np.ndarray]:
        """(pressure_pa, values) on the rising pressure branch, p > 0, finite values."""
        p = np.asarray(self.pressure_pa, dtype=float)
        y = np.asarray(getattr(self, quantity) if getattr(self, quantity) is not None
                       else np.full(p.shape, np.nan), dtype=float)
        n = len(p)
        if n == 0:
            return p, y
        rising = np.concatenate([[True], np.diff(p) > 0.0])
        stop = n if rising.all() else int(np.argmin(rising))
        p, y = p[:stop], y[:stop]
        keep = (p > 0.0) & np.isfinite(y) & np.isfinite(p)
        return p[keep], y[keep]

    @property
    def has_force(self) -> bool:
        if self.force_mn is None:
            return False
        return bool(np.isfinite(self.usable_points("force_mn")[1]).any())


def family_key(design: Design) -> tuple:
    """The family a design belongs to: everything the exponential model does not
    parametrise (material pair, T, b, h), as ``Design.family``."""
    return design.family


def select_angle_curves(curves: list[CurveData]) -> list[CurveData]:
    """Free-tip curves with at least 3 usable points; when a design was solved more than
    once (e.g. several mesh levels), the finest solve (largest ``mesh_rank``) is kept."""
    best: dict[tuple, CurveData] = {}
    for c in curves:
        if c.tip != "free" or len(c.usable_points()[0]) < 3:
            continue
        k = _design_identity(c.design)
        if k not in best or c.mesh_rank > best[k].mesh_rank:
            best[k] = c
    return list(best.values())


def select_force_curves(curves: list[CurveData]) -> list[CurveData]:
    """Curves with finite force, from the most common tip condition only (forces under
    different springs are different quantities); finest solve per design."""
    with_force = [c for c in curves if c.has_force and len(c.usable_points("force_mn")[0]) >= 3]
    if not with_force:
        return []
    tips: dict[tuple, int] = {}
    for c in with_force:
        tips[(c.tip, c.spring_k_n_per_m)] = tips.get((c.tip, c.spring_k_n_per_m), 0) + 1
    tip = max(tips, key=tips.__getitem__)
    best: dict[tuple, CurveData] = {}
    for c in with_force:
        if (c.tip, c.spring_k_n_per_m) != tip:
            continue
        k = _design_identity(c.design)
        if k not in best or c.mesh_rank > best[k].mesh_rank:
            best[k] = c
    return list(best.values())


def _design_identity(design: Design) -> tuple:
    d = design.validated()
    return (family_key(d), round(d.L_mm, 6), round(d.t_mm, 6), round(d.W_mm, 6),
            round(d.resolved_body_length_mm, 6), round(d.resolved_chamber_offset_mm, 6))


def by_physics(designs: list[Design]) -> list[Design]:
    """The designs with their materials named by physics, not by id alone: a material
    keeps its id when it equals the preset of that id, or (a custom id) is the only
    parameter set stored under it; otherwise it becomes ``<id>~<8 hex of its parameters>``, so
    that families (grouped by ``family_key``) never mix two materials of one name."""
    from dataclasses import replace

    from solver.materials import MATERIALS

    seen: dict[str, set[tuple]] = {}
    for d in designs:
        for m in (d.body_material, d.membrane_material):
            seen.setdefault(m.id, set()).add((m.mu_kpa, m.alpha))

    def named(m):
        preset = MATERIALS.get(m.id)
        if preset == m or (preset is None and len(seen[m.id]) == 1):
            return m
        tag = hashlib.sha256(repr((m.mu_kpa, m.alpha)).encode()).hexdigest()[:8]
        return replace(m, id=f"{m.id}~{tag}")

    return [replace(d, body_material=named(d.body_material),
                    membrane_material=named(d.membrane_material)) for d in designs]


def curves_from_store(path: str | os.PathLike, keys: Iterable[str] | None = None
                      ) -> tuple[list[CurveData], dict]:
    """Read every record of a CurveStore (or those with ``keys``) as CurveData; returns
    (curves, store metadata). Failed records keep their converged points (the rising
    branch up to the failure). Materials are named by physics (``by_physics``)."""
    from solver.store import CurveStore

    curves: list[CurveData] = []
    with CurveStore(path, mode="r") as db:
        metadata = dict(db.metadata)
        records = (list(db.records()) if keys is None
                   else [db.get(k) for k in sorted(set(keys))])
        designs = by_physics([rec.design for rec in records])
        for rec, design in zip(records, designs, strict=True):
            c = rec.curve
            s = rec.settings
            curves.append(CurveData(
                design=design, pressure_pa=np.asarray(c.pressure_pa, dtype=float),
                angle_deg=np.asarray(c.angle_deg, dtype=float),
                force_mn=np.asarray(c.force_mn, dtype=float), key=rec.key, tip=s.tip,
                spring_k_n_per_m=float(s.spring_k_n_per_m),
                mesh_rank=(int(s.mesh_level), MESH_DIVISIONS.index(s.mesh_divisions),
                           1 if s.element == "hex2" else 0),
                volume_ul=np.asarray(c.volume_ul, dtype=float)))
    return curves, metadata
