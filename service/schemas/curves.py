"""GET /v1/curves (filtered, paginated) and GET /v1/curves/{id}: the FE records."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field

from service.schemas.common import INLINE_MATERIAL_ID, QuerySchema, mm


class CurvesQuery(QuerySchema):
    """Filters (exact values, compared to 1e-6 mm) and the page."""

    L_mm: float | None = mm("L_mm", "chamber length")
    t_mm: float | None = mm("t_mm", "membrane thickness")
    T_mm: float | None = mm("T_mm", "body thickness")
    b_mm: float | None = mm("b_mm", "chamber width")
    h_mm: float | None = mm("h_mm", "chamber height")
    body_material: str | None = Field(None, pattern=INLINE_MATERIAL_ID)
    membrane_material: str | None = Field(None, pattern=INLINE_MATERIAL_ID)
    status: Literal["complete", "stopped", "failed"] | None = None
    offset: int = Field(0, ge=0, le=1_000_000, description="records to skip")
    limit: int = Field(50, ge=1, le=500, description="records per page")


class CurveSummary(BaseModel):
    id: str = Field(description="the record key: GET /v1/curves/{id}")
    L_mm: float = Field(description="chamber length, mm")
    t_mm: float = Field(description="membrane thickness, mm")
    T_mm: float = Field(description="body thickness above the chamber, mm")
    b_mm: float = Field(description="chamber width, mm")
    h_mm: float = Field(description="chamber height, mm")
    body_material: str = Field(description="body material id")
    membrane_material: str = Field(description="membrane material id")
    mesh_level: int = Field(description="FE mesh level (0 = coarsest)")
    element: str = Field(description="hex2 or hex1")
    status: str = Field(description="complete, stopped or failed")
    n_points: int = Field(description="converged steps, including the undeformed state")
    max_pressure_pa: float | None = Field(description="largest pressure reached, Pa")
    max_angle_deg: float | None = Field(description="the bending angle of largest magnitude "
                                        "reached, degrees, signed (negative for a pair "
                                        "that bends towards the membrane)")


class CurvePage(BaseModel):
    items: list[CurveSummary]
    total: int = Field(description="records matching the filters")
    offset: int = Field(description="records skipped")
    limit: int = Field(description="records per page")
    next_offset: int | None = Field(description="offset of the next page, or null")


class CurveDetail(BaseModel):
    id: str
    design: dict[str, Any]
    settings: dict[str, Any]
    curve: dict[str, Any] = Field(description="arrays per step; NaN is sent as null")
    provenance: dict[str, Any]
