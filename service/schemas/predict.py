"""POST /v1/predict and GET /v1/predict/plot: angle against pressure from a surrogate."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field

from service.schemas.common import MATERIAL_ID, DesignIn, Schema

MAX_PRESSURE_PA = 20000.0
Pressure = Annotated[float, Field(ge=0.0, le=MAX_PRESSURE_PA)]
MODEL = Field("emulator", pattern=MATERIAL_ID,
              description='"emulator" (the design-space emulator, default), "exponential" '
                          '(the paper\'s form fitted to the FE database; "fitted" is its old '
                          'name), "paper", or a saved calibrated model\'s name')
LEVEL = Field(0.95, ge=0.5, le=0.999, description="prediction band's coverage probability")


class PredictRequest(Schema):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"design": {"L_mm": 7.1, "t_mm": 0.5}, "pressures_pa": [500, 1000, 1500, 2000],
         "model": "fitted", "level": 0.95}]})

    design: DesignIn = Field(default_factory=lambda: DesignIn.model_validate({}))
    pressures_pa: list[Pressure] | None = Field(
        None, min_length=1, max_length=1000, description="chamber pressures, Pa (give "
        "exactly one of pressures_pa, volumes_ul, or times_s with flow_ul_s)")
    volumes_ul: list[Annotated[float, Field(ge=0.0, le=10000.0)]] | None = Field(
        None, min_length=1, max_length=1000, description="injected volumes, ul (the "
        "syringe pump's view; the emulator)")
    times_s: list[Annotated[float, Field(ge=0.0, le=1e5)]] | None = Field(
        None, min_length=1, max_length=1000, description="times since the pump started, "
        "s (with flow_ul_s)")
    flow_ul_s: float | None = Field(None, gt=0.0, le=1000.0, description="the pump's flow "
                                    "rate, ul/s (with times_s)")
    model: str = MODEL
    level: float = LEVEL


class Validity(BaseModel):
    in_domain: bool = Field(description="no flag raised: every answer is inside the FE data")
    flags: list[str] = Field([], description="machine-readable flags, e.g. past_fe_range")
    messages: list[str] = Field([], description="the flags in words")
    fe_limit_pa: float | None = Field(None, description="end of the FE's converged, stable "
                                      "range for this design, Pa (emulator)")
    fe_limit_angle_deg: float | None = Field(None, description="angle there, degrees")
    fe_stop_reason: str | None = Field(None, description="why the FE curves end there")


OptFloats = list[float | None] | None


class PredictResponse(BaseModel):
    model: str = Field(description="the model that answered")
    level: float = Field(description="the band's coverage probability")
    design: dict[str, Any] = Field(description="the design as resolved (all lengths, mm)")
    pressure_pa: list[float | None] = Field(description="chamber pressures, Pa")
    angle_deg: list[float | None] = Field(description="bending angle, degrees (null past "
                                          "the FE's range)")
    lower_deg: list[float | None] = Field(description="band's lower end, degrees")
    upper_deg: list[float | None] = Field(description="band's upper end, degrees")
    force_mn: OptFloats = Field(None, description="blocked-tip force, mN (null when the "
                                "model has none)")
    force_lower_mn: OptFloats = Field(None, description="force band's lower end, mN")
    force_upper_mn: OptFloats = Field(None, description="force band's upper end, mN")
    volume_ul: OptFloats = Field(None, description="injected volume at each point, ul")
    time_s: OptFloats = Field(None, description="time at the flow rate, s (times_s asked)")
    validity: Validity = Field(description="whether the answer is inside the model's domain")
    form: str | None = Field(None, description='model form: "exponential" (the paper\'s) '
                             'or "extended"')
    provenance: dict[str, Any] = Field(description="where the model came from (files by "
                                       "their name)")


class PlotQuery(Schema):
    """Query of GET /v1/predict/plot (a design with preset materials, and optional data)."""

    model_config = ConfigDict(strict=False)  # query values arrive as text

    L_mm: float = Field(7.1, ge=0.5, le=60.0, description="chamber length, mm")
    t_mm: float = Field(0.5, ge=0.05, le=5.0, description="membrane thickness, mm")
    T_mm: float = Field(1.0, ge=0.1, le=10.0, description="body thickness, mm")
    b_mm: float = Field(1.8, ge=0.1, le=20.0, description="chamber width, mm")
    h_mm: float = Field(0.15, ge=0.02, le=5.0, description="chamber height, mm")
    body_material: str = Field("pdms_1_10", pattern=MATERIAL_ID)
    membrane_material: str = Field("ecoflex_00_30", pattern=MATERIAL_ID)
    model: str = MODEL
    level: float = LEVEL
    p_max_pa: float = Field(2000.0, gt=0.0, le=MAX_PRESSURE_PA,
                            description="largest pressure plotted, Pa")
    nearby: int = Field(3, ge=0, le=10, description="FE curves of the family to overlay")
    measured_pressure_pa: list[Pressure] = Field(
        [], max_length=200, description="measured points to overlay: pressures, Pa")
    measured_angle_deg: list[Annotated[float, Field(ge=-360.0, le=360.0)]] = Field(
        [], max_length=200, description="measured points to overlay: angles, degrees")
