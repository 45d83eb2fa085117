"""GET /v1/curves (filtered, paginated) and GET /v1/curves/{id}: the stored FE records."""

from __future__ import annotations

import os
import pathlib
import re
from functools import lru_cache
from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter, Path, Query

from service.convert import jsonable
from service.deps import SettingsDep
from service.schemas import CurveDetail, CurvePage, CurvesQuery, CurveSummary
from service.store_access import open_store
from solver.errors import NotFoundError

router = APIRouter(prefix="/v1", tags=["curves"])

KEY = Path(description="the record key (hex; any other text is not found)",
           examples=["0123456789abcdef0123456789abcdef"])
KEY_PATTERN = re.compile(r"[0-9a-f]{1,64}")  # record keys; anything else is not found
TOL_MM = 1e-6


def _matches(row: dict[str, Any], query: CurvesQuery) -> bool:
    """``row`` is a store summary (flat design, material ids, status)."""
    d = row["design"]
    for name in ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm"):
        want = getattr(query, name)
        if want is not None and abs(float(d[name]) - want) > TOL_MM:
            return False
    if query.body_material and d["body_material"] != query.body_material:
        return False
    if query.membrane_material and d["membrane_material"] != query.membrane_material:
        return False
    return query.status is None or row["status"] == query.status


def _order(row: dict[str, Any]) -> tuple[Any, ...]:
    d = row["design"]
    return (d["body_material"], d["membrane_material"], d["L_mm"], d["t_mm"], row["key"])


def _peak(values: Any) -> float | None:
    a = np.asarray(values, float)
    a = a[np.isfinite(a)]
    return float(a.max()) if a.size else None


def summary(record: Any) -> CurveSummary:
    d, s, c = record.design, record.settings, record.curve
    return CurveSummary(id=record.key, L_mm=d.L_mm, t_mm=d.t_mm, T_mm=d.T_mm, b_mm=d.b_mm,
                        h_mm=d.h_mm, body_material=d.body_material.id,
                        membrane_material=d.membrane_material.id, mesh_level=s.mesh_level,
                        element=s.element, status=c.status, n_points=len(c),
                        max_pressure_pa=_peak(c.pressure_pa), max_angle_deg=_peak(c.angle_deg))


@lru_cache(maxsize=2)
def _index(path: str, inode: int, mtime_ns: int, size: int) -> tuple[dict[str, Any], ...]:
    """Every record's summary row (no curves), in page order, for one version of the file:
    the store publishes a new file on every write, so (inode, mtime, size) names a version.
    Reading the 2155 shipped rows' attributes takes 3-4 s; a page's request then reads only
    its own curves."""
    with open_store(pathlib.Path(path)) as db:
        return tuple(sorted(db.summaries(), key=_order))


@lru_cache(maxsize=4096)
def _summary(path: str, inode: int, mtime_ns: int, size: int, key: str) -> CurveSummary:
    with open_store(pathlib.Path(path)) as db:
        return summary(db.get(key))


def _version(path: pathlib.Path) -> tuple[str, int, int, int]:
    st = os.stat(path)
    return str(path), st.st_ino, st.st_mtime_ns, st.st_size


@router.get("/curves", response_model=CurvePage, summary="List FE records (filtered, paged)")
def list_curves(query: Annotated[CurvesQuery, Query()], settings: SettingsDep) -> CurvePage:
    """Records ordered by (materials, L_mm, t_mm, id); filters are exact (to 1e-6 mm).
    Only the page's curves are read from the file (and each once per file version)."""
    with open_store(settings.db_path):      # 503 when the file is missing or unreadable
        version = _version(settings.db_path)
    rows = [r for r in _index(*version) if _matches(r, query)]
    page = [_summary(*version, str(r["key"]))
            for r in rows[query.offset:query.offset + query.limit]]
    end = query.offset + len(page)
    return CurvePage(items=page, total=len(rows), offset=query.offset, limit=query.limit,
                     next_offset=end if end < len(rows) else None)


@router.get("/curves/{curve_id}", response_model=CurveDetail, summary="One FE record")
def get_curve(curve_id: Annotated[str, KEY], settings: SettingsDep) -> CurveDetail:
    """Design, settings, every per-step array of the curve (NaN as null), provenance."""
    with open_store(settings.db_path) as db:
        if not KEY_PATTERN.fullmatch(curve_id) or curve_id not in db:
            raise NotFoundError(f"no curve {curve_id!r}: GET /v1/curves lists them")
        record = db.get(curve_id)
    return CurveDetail(id=record.key, design=record.design.as_dict(),
                       settings=record.settings.as_dict(),
                       curve=jsonable(record.curve.as_dict()),
                       provenance=jsonable(dict(record.provenance)))
