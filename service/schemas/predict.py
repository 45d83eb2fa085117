"""POST /v1/predict and GET /v1/predict/plot: angle against pressure, injected volume or
time at a flow rate, from a surrogate."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from service.pump import AXES, MAX_FLOW_UL_S, MIN_FLOW_UL_S
from service.schemas.common import (
    INLINE_MATERIAL_ID,
    MATERIAL_ID,
    DesignIn,
    QueryBool,
    QuerySchema,
    Schema,
    mm,
)
from surrogate import hydraulics
from surrogate.band_level import ASKED_LEVELS
from surrogate.predictor import MAX_ASKED_VALUES

MAX_PRESSURE_PA = AXES["pressures_pa"][1]
Pressure = Annotated[float, Field(ge=0.0, le=MAX_PRESSURE_PA)]
MODEL = Field("emulator", pattern=MATERIAL_ID,
              description='"emulator" (the design-space emulator, default), "exponential" '
                          '(the paper\'s form fitted to the FE database; "fitted" is its old '
                          'name), "paper", or a saved calibrated model\'s name')
LEVEL = Field(0.95, ge=ASKED_LEVELS[0], le=ASKED_LEVELS[1],
              description="prediction band's coverage probability")


def _axis(name: str) -> Any:
    lo, hi, _ = AXES[name]
    return Annotated[float, Field(ge=lo, le=hi)]


def _inlet(name: str, default: float | None, description: str) -> Any:
    """An inlet field with the limits of ``surrogate.hydraulics.LIMITS``."""
    lo, hi = hydraulics.LIMITS[name]
    return Field(default, ge=lo, le=hi, description=description)


class InletIn(Schema):
    """The path from the pump's gauge to the chamber (Hagen-Poiseuille, laminar): the
    inlet channel (default the paper's: 0.5 mm wide, 3 mm long, 0.15 mm high) and, with
    ``tubing_length_mm`` > 0, round tubing of bore ``tubing_bore_mm``; water at 20 degC by
    default."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"tubing_length_mm": 500, "tubing_bore_mm": 0.5}]})

    channel_width_mm: float = _inlet("channel_width_mm", hydraulics.CHANNEL_WIDTH_MM,
                                     "inlet channel width, mm")
    channel_length_mm: float = _inlet("channel_length_mm", hydraulics.CHANNEL_LENGTH_MM,
                                      "inlet channel length, mm")
    channel_height_mm: float = _inlet("channel_height_mm", hydraulics.CHANNEL_HEIGHT_MM,
                                      "inlet channel height, mm")
    tubing_length_mm: float = _inlet("tubing_length_mm", 0.0, "tubing length, mm (0: none)")
    tubing_bore_mm: float | None = _inlet("tubing_bore_mm", None, "tubing inner diameter, "
                                          "mm (with tubing_length_mm)")
    viscosity_pa_s: float = _inlet("viscosity_pa_s", hydraulics.WATER_VISCOSITY_PA_S,
                                   "the fluid's dynamic viscosity, Pa s (default water at "
                                   "20 degC)")


FLOW = Field(None, ge=MIN_FLOW_UL_S, le=MAX_FLOW_UL_S, description="the pump's flow rate, "
             "ul/s (with times_s; with any axis it adds time_s = volume / flow, and with "
             "inlet the pump-gauge pressure)")
INLET = Field(None, description="the inlet's hydraulic resistance R: with flow_ul_s the "
              "answer adds pump_pressure_pa = chamber pressure + R Q")


class PredictRequest(Schema):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"design": {"L_mm": 7.1, "t_mm": 0.5}, "pressures_pa": [500, 1000, 1500, 2000],
         "model": "emulator", "level": 0.95},
        {"design": {"L_mm": 7.1, "t_mm": 0.5}, "volumes_ul": [2, 5, 10, 20]},
        {"design": {"L_mm": 7.1, "t_mm": 0.5}, "times_s": [1, 2, 4, 6, 8, 10],
         "flow_ul_s": 2.5},
        {"design": {"L_mm": 7.1, "t_mm": 0.5}, "times_s": [2, 4, 8], "flow_ul_s": 2.5,
         "inlet": {"tubing_length_mm": 500, "tubing_bore_mm": 0.5}},
        {"design": {"L_mm": 7.1, "t_mm": 0.5}, "pressures_pa": [800, 1200],
         "pressures_at": "pump_gauge", "flow_ul_s": 2.5, "inlet": {}}]})

    design: DesignIn = Field(default_factory=lambda: DesignIn.model_validate({}))
    pressures_pa: list[_axis("pressures_pa")] | None = Field(  # type: ignore[valid-type]
        None, min_length=1, max_length=MAX_ASKED_VALUES, description="pressures, Pa, at the "
        "chamber (or the pump gauge: pressures_at) (give exactly one of pressures_pa, "
        "volumes_ul, or times_s with flow_ul_s)")
    volumes_ul: list[_axis("volumes_ul")] | None = Field(  # type: ignore[valid-type]
        None, min_length=1, max_length=MAX_ASKED_VALUES, description="injected volumes, ul, whole "
        "actuator (the syringe pump's view; the emulator)")
    times_s: list[_axis("times_s")] | None = Field(  # type: ignore[valid-type]
        None, min_length=1, max_length=MAX_ASKED_VALUES, description="times since the pump started "
        "from the undeformed actuator, s (with flow_ul_s; volume = flow x time)")
    flow_ul_s: float | None = FLOW
    inlet: InletIn | None = INLET
    pressures_at: Literal["chamber", "pump_gauge"] = Field(
        "chamber", description="where pressures_pa were read: the chamber, or a gauge at "
        "the pump (then chamber = given - R Q; needs inlet and flow_ul_s)")
    model: str = MODEL
    level: float = LEVEL


class Validity(BaseModel):
    in_domain: bool = Field(description="the design is inside the model's domain (the "
                            "emulator's box; the exponential model's fitted ranges); asked "
                            "points past the FE's range do not change it: they are flagged "
                            "past_fe_range")
    flags: list[str] = Field([], description="machine-readable flags, e.g. past_fe_range")
    messages: list[str] = Field([], description="the flags in words")
    fe_limit_pa: float | None = Field(None, description="end of the FE's converged, stable "
                                      "range for this design, Pa (emulator)")
    fe_limit_angle_deg: float | None = Field(None, description="angle there, degrees "
                                             "(signed as the design's angles: negative for "
                                             "a design bending towards the membrane)")
    fe_stop_reason: str | None = Field(None, description="why the FE curves end there")
    fe_limit_volume_ul: float | None = Field(None, description="injected volume there, ul "
                                             "(wherever the answer gives volume_ul)")
    pressure_maximum_pa: float | None = Field(None, description="the pressure maximum of a "
                                              "limit point (flag past_pressure_maximum), Pa")
    pressure_maximum_volume_ul: float | None = Field(None, description="the injected volume "
                                                     "at that maximum, ul")
    high_stretch_from_deg: float | None = Field(
        None, description="the angle from which the design's emulated membrane stretch "
        "enters the range where FE curves often end in Newton failures (flag "
        "high_membrane_stretch), degrees, signed as the design's angles")
    high_stretch_from_pa: float | None = Field(None, description="the chamber pressure "
                                               "there, Pa")


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
    time_s: OptFloats = Field(None, description="time at the flow rate, s (flow_ul_s given)")
    asked: str | None = Field(None, description="the axis asked: pressures_pa, volumes_ul or "
                              "times_s")
    flow_ul_s: float | None = Field(None, description="the pump's flow rate, ul/s")
    pressure_sites: dict[str, str] = Field(
        {"pressure_pa": "chamber"}, description="which pressure each pressure field reports: "
        "pressure_pa the chamber's, pump_pressure_pa the pump gauge's")
    pump_pressure_pa: OptFloats = Field(None, description="what a gauge at the pump reads, "
                                        "Pa: chamber pressure + R Q (inlet given; null "
                                        "before the line's flow is steady, flag "
                                        "pump_pressure_not_steady)")
    inlet: dict[str, Any] | None = Field(None, description="the inlet as used: dimensions, "
                                         "resistance_pa_per_ul_s, pressure_drop_pa (R Q), "
                                         "reynolds_number, time_constant_s (tau = R C, C the "
                                         "line's fluid's compressibility: a lower bound)")
    validity: Validity = Field(description="whether the answer is inside the model's domain")
    form: str | None = Field(None, description='model form: "exponential" (the paper\'s) '
                             'or "extended"')
    provenance: dict[str, Any] = Field(description="where the model came from (files by "
                                       "their name)")


class PlotQuery(QuerySchema):
    """Query of GET /v1/predict/plot (a design with preset materials, and optional data)."""

    L_mm: float = mm("L_mm", "chamber length", 7.1)  # type: ignore[assignment]
    t_mm: float = mm("t_mm", "membrane thickness", 0.5)  # type: ignore[assignment]
    T_mm: float = mm("T_mm", "body thickness", 1.0)  # type: ignore[assignment]
    b_mm: float = mm("b_mm", "chamber width", 1.8)  # type: ignore[assignment]
    h_mm: float = mm("h_mm", "chamber height", 0.15)  # type: ignore[assignment]
    W_mm: float = mm("W_mm", "actuator width (the body length scales with it, as in "
                     "/v1/predict)", 3.0)  # type: ignore[assignment]
    body_material: str = Field("pdms_1_10", pattern=INLINE_MATERIAL_ID)
    membrane_material: str = Field("ecoflex_00_30", pattern=INLINE_MATERIAL_ID)
    model: str = MODEL
    level: float = LEVEL
    p_max_pa: float = Field(2000.0, gt=0.0, le=MAX_PRESSURE_PA,
                            description="largest pressure plotted, Pa (without flow_ul_s)")
    nearby: int = Field(3, ge=0, le=10, description="FE curves of the family to overlay")
    flow_ul_s: float | None = Field(None, ge=MIN_FLOW_UL_S, le=MAX_FLOW_UL_S, description="the "
                                    "pump's flow rate, ul/s: plot angle against time, with "
                                    "the pressure on a second axis (the paper's protocol)")
    t_max_s: float = Field(10.0, gt=0.0, le=AXES["times_s"][1], description="largest time "
                           "plotted, s (with flow_ul_s)")
    inlet: QueryBool = Field(False, description="with flow_ul_s: also the pump-gauge pressure "
                        "through the paper's inlet channel (water), chamber + R Q")
    measured_pressure_pa: list[Pressure] = Field(
        [], max_length=200, description="measured points to overlay: pressures, Pa")
    measured_angle_deg: list[Annotated[float, Field(ge=-360.0, le=360.0)]] = Field(
        [], max_length=200, description="measured points to overlay: angles, degrees")
