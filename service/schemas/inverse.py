"""POST /v1/inverse (ranked designs for a target) and POST /v1/inverse/pressure (the
pressure at which one design reaches given angles)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, WithJsonSchema, model_validator

from service.errors import short_input
from service.pump import MAX_ANGLE_DEG, MAX_FLOW_UL_S, MIN_FLOW_UL_S
from service.schemas.common import INLINE_MATERIAL_ID, DesignIn, Schema
from service.schemas.predict import INLET, LEVEL, MODEL, InletIn
from solver.design import LIMITS_MM
from solver.design_space import BOX_MM, STIFFNESS_SCALE_LIMITS, STIFFNESS_SCALE_RANGE
from surrogate.predictor import FE_VOLUME_STOP_UL, MAX_ASKED_VALUES
from surrogate.search.design_search import N_RESULTS_MAX
from surrogate.search.design_target import (
    DEFAULT_KIND,
    KINDS,
    MAX_TARGET,
    OBJECTIVES,
)
from surrogate.search.ranking import SCORE_MEANING
from surrogate.volume_control import MAX_TIME_S

Angle = Annotated[float, Field(ge=-MAX_ANGLE_DEG, le=MAX_ANGLE_DEG)]
OptFloats = list[float | None] | None


class TargetIn(Schema):
    """What the design must do: ``angle_at_pressure`` (reach angle_deg at pressure_pa),
    ``pressure_budget`` (reach angle_deg at no more than pressure_pa) or
    ``force_at_pressure`` (force_mn at pressure_pa; needs force curves); a syringe pump's:
    ``angle_at_volume`` (reach angle_deg at volume_ul injected), ``volume_budget`` (with
    no more than volume_ul), ``angle_at_time`` (after time_s at flow_ul_s, from the
    undeformed state: volume = flow x time) or ``time_budget`` (within time_s at
    flow_ul_s). Each kind takes its own fields and refuses the others."""

    kind: Literal[KINDS] = DEFAULT_KIND  # type: ignore[valid-type]
    pressure_pa: float | None = Field(None, gt=0.0, le=MAX_TARGET["pressure_pa"],
                                      description="pressure, Pa (the targets by pressure)")
    volume_ul: float | None = Field(
        None, gt=0.0, le=FE_VOLUME_STOP_UL, description="injected volume, ul, whole "
        "actuator (angle_at_volume, volume_budget); at most the FE's volume stop")
    time_s: float | None = Field(None, gt=0.0, le=MAX_TIME_S, description="time at flow_ul_s "
                                 "from the undeformed state, s (angle_at_time, time_budget)")
    flow_ul_s: float | None = Field(None, ge=MIN_FLOW_UL_S, le=MAX_FLOW_UL_S,
                                    description="the pump's flow rate, ul/s (with time_s)")
    angle_deg: float | None = Field(
        None, ge=-MAX_TARGET["angle_deg"], le=MAX_TARGET["angle_deg"],
        description="target angle, degrees; its sign is the way the design bends: positive "
                    "away from the membrane, negative towards it (the reversed pair)")
    force_mn: float | None = Field(None, ge=-MAX_TARGET["force_mn"], le=MAX_TARGET["force_mn"],
                                   description="target blocked-tip force, mN (signed as the "
                                               "angle)")


# what an item of material_pairs may be, in words (service.errors.FIELD_FORMS
# "material_pairs.*": an item's error is told this, not its list's "1-20 values")
PAIR_FORMS = ('the text "body/membrane" (e.g. "pdms_1_10/ecoflex_00_30"), or an object of '
              "body_material, membrane_material")


class MaterialPair(Schema):
    """A (body, membrane) pair: an object, or the text "body/membrane" the CLI's --pair,
    the answer's ``pair`` and ``best_reachable`` use."""

    body_material: str = Field(pattern=INLINE_MATERIAL_ID)
    membrane_material: str = Field(pattern=INLINE_MATERIAL_ID)

    @model_validator(mode="before")
    @classmethod
    def _from_text(cls, value: Any) -> Any:
        if isinstance(value, str):
            parts = value.split("/")
            if len(parts) != 2:
                raise ValueError(f"{short_input(value)} is not of this form")
            return {"body_material": parts[0].strip(), "membrane_material": parts[1].strip()}
        return value


_ID = INLINE_MATERIAL_ID.removeprefix("^").removesuffix("$")
# the published schema admits both forms the validator reads: a schema-checking client
# sending the text "body/membrane" (the CLI's --pair, the examples) is not told it is wrong
PairIn = Annotated[MaterialPair, WithJsonSchema({"anyOf": [
    MaterialPair.model_json_schema(),
    {"type": "string", "pattern": rf"^\s*{_ID}\s*/\s*{_ID}\s*$",
     "description": 'the text "body/membrane", e.g. "pdms_1_10/ecoflex_00_30"'}]})]


def _bound_list(lo: float, hi: float) -> Any:
    """[low, high] within (lo, hi), or None: a search bound's type."""
    return list[Annotated[float, Field(ge=lo, le=hi)]] | None


# a search bound may state any design the solver takes (LIMITS_MM); the search covers
# its part inside the emulator's box (BOX_MM) and says so (design_search.SearchBounds)
L_BOUNDS = _bound_list(*LIMITS_MM["L_mm"])
T_BOUNDS = _bound_list(*LIMITS_MM["T_mm"])
THIN_BOUNDS = _bound_list(*LIMITS_MM["t_mm"])
B_BOUNDS = _bound_list(*LIMITS_MM["b_mm"])
H_BOUNDS = _bound_list(*LIMITS_MM["h_mm"])
SCALE_BOUNDS = _bound_list(*STIFFNESS_SCALE_LIMITS)


def _box_field(name: str, what: str) -> Any:
    lo, hi = BOX_MM[name]
    return Field(None, min_length=2, max_length=2, description=f"[low, high] {what}, mm "
                 f"(default: the emulator's box, {lo:g}..{hi:g})")


class InverseRequest(Schema):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"target": {"kind": "angle_at_pressure", "pressure_pa": 1500, "angle_deg": 45},
         "L_bounds_mm": [4.1, 15.1], "t_bounds_mm": [0.5, 1.0], "n_results": 3},
        {"target": {"kind": "volume_budget", "volume_ul": 20, "angle_deg": 45},
         "n_results": 3},
        {"target": {"kind": "angle_at_time", "time_s": 8, "flow_ul_s": 2.5, "angle_deg": 45},
         "L_bounds_mm": [10, 14], "material_pairs": ["pdms_1_10/ecoflex_00_30"],
         "n_results": 3}]})

    target: TargetIn
    L_bounds_mm: L_BOUNDS = _box_field("L_mm", "chamber length")
    t_bounds_mm: THIN_BOUNDS = _box_field("t_mm", "membrane thickness")
    T_bounds_mm: T_BOUNDS = _box_field("T_mm", "body thickness above the chamber")
    b_bounds_mm: B_BOUNDS = _box_field("b_mm", "chamber width")
    h_bounds_mm: H_BOUNDS = _box_field("h_mm", "chamber height")
    body_stiffness_scale_bounds: SCALE_BOUNDS = Field(
        None, min_length=2, max_length=2, description="[low, high] body mu / preset mu "
        "(default [1, 1]: the preset; the box allows "
        f"{STIFFNESS_SCALE_RANGE[0]:g}..{STIFFNESS_SCALE_RANGE[1]:g})")
    membrane_stiffness_scale_bounds: SCALE_BOUNDS = Field(
        None, min_length=2, max_length=2, description="[low, high] membrane mu / "
        "preset mu (default [1, 1])")
    material_pairs: list[PairIn] | None = Field(
        None, min_length=1, max_length=20, description="allowed pairs (default: all fitted)")
    objective: Literal[OBJECTIVES] | None = Field(  # type: ignore[valid-type]
        None, description="ranking (default: certainty; pressure for pressure_budget, "
        "volume for volume_budget and time_budget)")
    n_results: int = Field(5, ge=1, le=N_RESULTS_MAX, description="designs returned at most")
    model: str = MODEL
    level: float = LEVEL


class Candidate(BaseModel):
    rank: int = Field(description="1 = best by the objective")
    L_mm: float = Field(description="chamber length, mm")
    t_mm: float = Field(description="membrane thickness, mm")
    T_mm: float | None = Field(None, description="body thickness above the chamber, mm")
    b_mm: float | None = Field(None, description="chamber width, mm")
    h_mm: float | None = Field(None, description="chamber height, mm")
    body_material: str = Field(description="body material preset id")
    membrane_material: str = Field(description="membrane material preset id")
    body_stiffness_scale: float | None = Field(None, description="body mu / the preset's")
    membrane_stiffness_scale: float | None = Field(None, description="membrane mu / the "
                                                   "preset's")
    design: dict[str, Any] | None = Field(None, description="the design, as /v1/predict "
                                          "takes it (lengths mm, materials inline)")
    family: str = Field(description="the material group or fitted family it belongs to")
    score: float | None = Field(description="the objective's value, lower ranks first: "
                                + "; ".join(f"{k}: {v}" for k, v in SCORE_MEANING.items()))
    pressure_needed_pa: float | None = Field(description="pressure that meets the target, Pa")
    pressure_lower_pa: float | None = Field(description="its band's lower edge, Pa")
    pressure_upper_pa: float | None = Field(description="its band's upper edge, Pa")
    value_at_pressure: float | None = Field(
        description="predicted angle (deg) or force (mN) at the target pressure (null for "
                    "a pump's target: angle_at_volume_deg)")
    value_lower: float | None = Field(description="band's lower edge (deg or mN)")
    value_upper: float | None = Field(description="band's upper edge (deg or mN)")
    volume_needed_ul: float | None = Field(None, description="a pump's target: injected "
                                           "volume that gives the target angle, ul")
    volume_lower_ul: float | None = Field(None, description="its band's lower edge, ul")
    volume_upper_ul: float | None = Field(None, description="its band's upper edge, ul")
    time_needed_s: float | None = Field(None, description="a time target: time to the "
                                        "target angle at flow_ul_s, s")
    time_lower_s: float | None = Field(None, description="its band's lower edge, s")
    time_upper_s: float | None = Field(None, description="its band's upper edge, s")
    angle_at_volume_deg: float | None = Field(None, description="a pump's target: angle at "
                                              "the target volume, deg (null past the FE's "
                                              "range)")
    angle_at_volume_lower_deg: float | None = Field(None, description="its band's lower "
                                                    "edge, deg")
    angle_at_volume_upper_deg: float | None = Field(None, description="its band's upper "
                                                    "edge, deg")
    pressure_at_volume_pa: float | None = Field(None, description="a pump's target: chamber "
                                                "pressure at the target volume, Pa")
    change_per_0_01_mm: dict[str, float] | None = Field(
        None, description="the value's change (deg or mN) when one length (L_mm, t_mm, "
        "T_mm, b_mm, h_mm) is made 0.01 mm larger, the others kept: what a mould's "
        "tolerance does to the answer (design-space search; null otherwise)")
    validity: dict[str, Any] = Field(description="in_domain, flags, messages")
    curve: dict[str, Any] = Field(description="predicted curve from 0 Pa (a pump's target: "
                                  "from 0 ul, by injected volume) with its band")


class InverseResponse(BaseModel):
    model: str
    level: float
    objective: str
    feasible: bool
    explanation: str
    candidates: list[Candidate]
    best_reachable: dict[str, Any] = Field(
        description="when infeasible: the largest and smallest value reachable")
    n_evaluated: int


class PressureRequest(Schema):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"design": {"L_mm": 7.1, "t_mm": 0.5}, "angles_deg": [10, 45, 90]},
        {"design": {"L_mm": 7.1, "t_mm": 0.5}, "angles_deg": [45], "flow_ul_s": 2.5,
         "inlet": {}}]})

    design: DesignIn = Field(default_factory=lambda: DesignIn.model_validate({}))
    angles_deg: list[Angle] = Field(min_length=1, max_length=MAX_ASKED_VALUES,
                                    description="target angles, degrees")
    flow_ul_s: float | None = Field(None, ge=MIN_FLOW_UL_S, le=MAX_FLOW_UL_S,
                                    description="the pump's flow rate, ul/s: adds the time "
                                    "needed, s")
    inlet: InletIn | None = INLET
    model: str = MODEL
    level: float = LEVEL


class PressureResponse(BaseModel):
    model: str = Field(description="the model that answered")
    level: float = Field(description="the band's coverage probability")
    design: dict[str, Any] = Field(description="the design as resolved (lengths, mm)")
    angle_deg: list[float] = Field(description="the target angles, degrees")
    pressure_pa: list[float | None] = Field(description="pressure for each angle, Pa (null: "
                                            "not reachable)")
    lower_pa: list[float | None] = Field(description="band's lower edge, Pa")
    upper_pa: list[float | None] = Field(description="band's upper edge, Pa")
    volume_ul: OptFloats = Field(None, description="injected volume for each angle, ul (the "
                                 "emulator)")
    volume_lower_ul: OptFloats = Field(None, description="its band's lower edge, ul")
    volume_upper_ul: OptFloats = Field(None, description="its band's upper edge, ul")
    flow_ul_s: float | None = Field(None, description="the pump's flow rate, ul/s")
    time_s: OptFloats = Field(None, description="time to reach each angle at flow_ul_s from "
                              "the undeformed actuator, s")
    time_lower_s: OptFloats = Field(None, description="its band's lower edge, s")
    time_upper_s: OptFloats = Field(None, description="its band's upper edge, s")
    pressure_sites: dict[str, str] = Field(
        {"pressure_pa": "chamber"}, description="which pressure each pressure field reports")
    pump_pressure_pa: OptFloats = Field(None, description="what a gauge at the pump reads "
                                        "while pumping at flow_ul_s, Pa (inlet given)")
    inlet: dict[str, Any] | None = Field(None, description="the inlet as used (R, R Q, Re, "
                                         "the line's time constant tau)")
    validity: dict[str, Any] = Field(description="in_domain, flags, messages")
