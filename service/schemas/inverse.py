"""POST /v1/inverse: designs (or the pressure) that reach a target angle."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from service.schemas.common import DesignIn, Schema
from service.schemas.predict import LEVEL, MODEL


class InverseRequest(Schema):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"target_angle_deg": 45.0, "design": {"L_mm": 7.1, "t_mm": 0.5}}]})

    target_angle_deg: float = Field(ge=-360.0, le=360.0, description="target angle, degrees")
    design: DesignIn = Field(default_factory=DesignIn)
    model: str = MODEL
    level: float = LEVEL


class InverseResponse(BaseModel):
    model: str
    level: float
    target_angle_deg: float
    design: dict[str, Any]
    pressure_pa: float | None
    lower_pa: float | None
    upper_pa: float | None
    validity: dict[str, Any]
