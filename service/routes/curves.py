"""GET /v1/curves (filtered, paginated) and GET /v1/curves/{id}: the stored FE records."""

from __future__ import annotations

import re
import threading
from collections import OrderedDict
from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter, Path, Query

from service.convert import jsonable
from service.deps import SettingsDep
from service.errors import short_input
from service.schemas import CurveDetail, CurvePage, CurvesQuery, CurveSummary
from service.store_access import file_version, open_store, summary_rows
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
    """The value of largest magnitude, with its sign (a reversed pair's curve runs to
    -94 deg: its extreme is -94, not the -0.0 of its first step); None when none is
    finite."""
    a = np.asarray(values, float)
    a = a[np.isfinite(a)]
    return float(a[np.argmax(np.abs(a))]) + 0.0 if a.size else None


def summary(record: Any) -> CurveSummary:
    d, s, c = record.design, record.settings, record.curve
    return CurveSummary(id=record.key, L_mm=d.L_mm, t_mm=d.t_mm, T_mm=d.T_mm, b_mm=d.b_mm,
                        h_mm=d.h_mm, body_material=d.body_material.id,
                        membrane_material=d.membrane_material.id, mesh_level=s.mesh_level,
                        element=s.element, status=c.status, n_points=len(c),
                        max_pressure_pa=_peak(c.pressure_pa), max_angle_deg=_peak(c.angle_deg))


# Summary rows (``store_access.summary_rows``) in page order, and page items, of one
# version of the database file: a request reads only the page items not seen before,
# through the one store it opened.
_ORDERED: dict[tuple, tuple[dict[str, Any], ...]] = {}
_ITEMS: OrderedDict[tuple, CurveSummary] = OrderedDict()
_ITEMS_KEPT = 4096
_LOCK = threading.Lock()


def _index(version: tuple, db: Any) -> tuple[dict[str, Any], ...]:
    """Every record's summary row (no curves), in page order."""
    with _LOCK:
        rows = _ORDERED.get(version)
    if rows is None:
        rows = tuple(sorted(summary_rows(version, db), key=_order))
        with _LOCK:
            _ORDERED.clear()          # one version kept: the current file
            _ORDERED[version] = rows
    return rows


def _item(version: tuple, key: str, db: Any) -> CurveSummary:
    with _LOCK:
        item = _ITEMS.get((version, key))
    if item is None:
        item = summary(db.get(key))
        with _LOCK:
            _ITEMS[(version, key)] = item
            while len(_ITEMS) > _ITEMS_KEPT:
                _ITEMS.popitem(last=False)
    return item


@router.get("/curves", response_model=CurvePage, summary="List FE records (filtered, paged)")
def list_curves(query: Annotated[CurvesQuery, Query()], settings: SettingsDep) -> CurvePage:
    """Records ordered by (materials, L_mm, t_mm, id); filters are exact (to 1e-6 mm).
    Only the page's curves are read from the file (and each once per file version)."""
    # the version before opening: a write in between caches newer rows under the older
    # version, which no later request asks for (the reverse would serve stale rows)
    try:
        version = file_version(settings.db_path)
    except OSError:
        version = None
    with open_store(settings.db_path) as db:    # 503 when missing or unreadable
        version = version or file_version(settings.db_path)
        rows = [r for r in _index(version, db) if _matches(r, query)]
        page = [_item(version, str(r["key"]), db)
                for r in rows[query.offset:query.offset + query.limit]]
    end = query.offset + len(page)
    return CurvePage(items=page, total=len(rows), offset=query.offset, limit=query.limit,
                     next_offset=end if end < len(rows) else None)


@router.get("/curves/{curve_id}", response_model=CurveDetail, summary="One FE record")
def get_curve(curve_id: Annotated[str, KEY], settings: SettingsDep) -> CurveDetail:
    """Design, settings, every per-step array of the curve (NaN as null), provenance."""
    with open_store(settings.db_path) as db:
        if not KEY_PATTERN.fullmatch(curve_id) or curve_id not in db:
            raise NotFoundError(f"no curve {short_input(curve_id)}: GET /v1/curves lists "
                                "them")
        record = db.get(curve_id)
    return CurveDetail(id=record.key, design=record.design.as_dict(),
                       settings=record.settings.as_dict(),
                       curve=jsonable(record.curve.as_dict()),
                       provenance=jsonable(dict(record.provenance)))
