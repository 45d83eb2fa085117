"""Shared request parts: a design, an inline Ogden material, solver settings."""

from __future__ import annotations

from typing import Annotated, Literal, get_args

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationInfo, field_validator
from pydantic_core import PydanticCustomError

from service.errors import QUERY_BOOL_ERROR
from solver.design import LIMITS_MM
from solver.materials import MATERIAL_ID_PATTERN
from solver.number_text import (
    INTEGER_FORM,
    NUMBER_FORM,
    WrittenNumber,
    is_integer_text,
    is_number_text,
    unheld_words,
    written_float,
)
from solver.settings import MAX_MESH_LEVEL, MESH_DIVISIONS, SolverSettings

MATERIAL_ID = r"^[A-Za-z0-9_][A-Za-z0-9_.\-]{0,63}$"  # a name, never a path
# An inline material's id: a name, or a preset scaled as the store and the design search
# name it (``ecoflex_00_30*1.5``: solver.design_space.scaled_material), so that a design
# /v1/inverse answers is taken back by /v1/predict.
INLINE_MATERIAL_ID = MATERIAL_ID_PATTERN
# The patterns in words (a validation error states these instead of the pattern).
NAME_WORDS = "1-64 letters, digits, '_', '.', '-', not starting with '.' or '-'"


def text_forms() -> dict[str, str]:
    """Text field name -> the form its pattern allows, in words: a layer's material is a
    preset id (solver.materials.MATERIALS) or one scaled (an inline material is an
    object); an inline material's id is a name; a model is a built-in's, by its current
    name (service.models.BUILT_IN_MODELS), or a saved one's name."""
    from service.models import BUILT_IN_MODELS
    from solver.materials import MATERIALS

    layer = (", ".join(sorted(MATERIALS)) + ", or a preset scaled as <preset>*<scale> "
             "(pdms_1_10*1.2)")
    return {"body_material": layer, "membrane_material": layer,
            "id": f"a name of {NAME_WORDS}, optionally *<scale>",
            "model": ", ".join(BUILT_IN_MODELS) + f", or a saved model's name ({NAME_WORDS})"}


class Schema(BaseModel):
    """Base of every request schema: unknown fields are refused, NaN and infinity too, and
    values are strict JSON types: a number field takes a JSON number (an integer too),
    never ``true`` or the string ``"7.1"``; an integer field never takes 0.5. Query
    models (whose values arrive as text) relax ``strict``."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)


class QuerySchema(Schema):
    """Base of a query model: its values arrive as text, so ``strict`` is relaxed, and a
    number field's text is read by the one rule of numbers written as text
    (``solver.number_text``: ASCII decimal digits), as the command line reads it; in
    lax mode pydantic read ``L_mm=7_1`` as 71 mm."""

    model_config = ConfigDict(strict=False)

    @field_validator("*", mode="before")
    @classmethod
    def _numbers_as_text(cls, value: object, info: ValidationInfo) -> object:
        kind = None if info.field_name is None else _number_kind(
            cls.model_fields[info.field_name].annotation)
        if kind is None:
            return value
        if isinstance(value, list):
            return [query_number(v, kind) for v in value]
        return query_number(value, kind)


def query_number(value: object, kind: type = float) -> object:
    """A query model's number field (``kind`` float or int): text not written as the
    command line writes such a number (NUMBER_FORM; INTEGER_FORM: pydantic read
    ``limit=1.0`` as 1, which ``-n 1.0`` refuses) is refused; anything else goes on to the
    field's own checks (its type, finiteness and range). A number whose text a float does
    not hold (``1e-400``, read as 0) is refused as written, as in a JSON body
    (``service.unheld_numbers``)."""
    if not isinstance(value, str):
        return value
    if kind is int and not is_integer_text(value):
        raise PydanticCustomError("number_text",
                                  f"Input should be a whole number in {INTEGER_FORM}")
    if not is_number_text(value):
        raise PydanticCustomError("number_text", f"Input should be a number in {NUMBER_FORM}")
    if kind is float and isinstance(number := written_float(value), WrittenNumber):
        raise PydanticCustomError("number_text", unheld_words(number))  # as a body's 1e-400
    return value


def _number_kind(annotation: object) -> type | None:
    """float or int: the number a field's type holds (a bool is neither); None if none."""
    if annotation in (float, int):
        return annotation  # type: ignore[return-value]
    return next((k for k in map(_number_kind, get_args(annotation)) if k), None)


QUERY_BOOL_WORDS = {"true": True, "false": False}


def _query_bool(value: object) -> object:
    """A query parameter's yes or no, spelt as JSON spells it (``true``, ``false``): in
    lax mode pydantic read ``yes``, ``on``, ``1``, ``True``, ``f`` too, so a typo such as
    ``inlet=no-thanks`` was refused but ``inlet=off`` quietly meant false."""
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value in QUERY_BOOL_WORDS:
        return QUERY_BOOL_WORDS[value]
    raise PydanticCustomError(QUERY_BOOL_ERROR, "Input should be true or false")


# a bool query parameter: exactly true or false (a JSON body's bools are strict already)
QueryBool = Annotated[bool, BeforeValidator(_query_bool)]


def mm(name: str, description: str, default: float | None = None) -> object:
    """A length field (mm) with the design limits of ``solver.design.LIMITS_MM``."""
    lo, hi = LIMITS_MM[name]
    return Field(default, ge=lo, le=hi, description=f"{description}, mm")


class MaterialIn(Schema):
    """A custom N-term Ogden material (mu in kPa), given inline instead of a preset id."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"id": "my_silicone", "mu_kpa": [1.2, 0.01], "alpha": [3.0, 13.0]}]})

    id: str = Field("custom", pattern=INLINE_MATERIAL_ID,
                    description="a name for the material (a scaled preset: <preset>*<scale>)")
    mu_kpa: list[Annotated[float, Field(ge=-1e6, le=1e6)]] = Field(
        min_length=1, max_length=6, description="Ogden moduli mu_p, kPa")
    alpha: list[Annotated[float, Field(ge=-50, le=50)]] = Field(
        min_length=1, max_length=6, description="Ogden exponents alpha_p (dimensionless)")


MaterialRef = Annotated[str, Field(pattern=INLINE_MATERIAL_ID)] | MaterialIn


class DesignIn(Schema):
    """An actuator design; omitted fields take the paper's standard design (Table 3)."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"L_mm": 7.1, "t_mm": 0.5, "body_material": "pdms_1_10",
         "membrane_material": "ecoflex_00_30"}]})

    L_mm: float = mm("L_mm", "chamber length", 7.1)  # type: ignore[assignment]
    t_mm: float = mm("t_mm", "membrane thickness", 0.5)  # type: ignore[assignment]
    T_mm: float = mm("T_mm", "body thickness above the chamber", 1.0)  # type: ignore[assignment]
    b_mm: float = mm("b_mm", "chamber width", 1.8)  # type: ignore[assignment]
    h_mm: float = mm("h_mm", "chamber height", 0.15)  # type: ignore[assignment]
    W_mm: float = mm("W_mm", "actuator width", 3.0)  # type: ignore[assignment]
    body_length_mm: float | None = mm(  # type: ignore[assignment]
        "body_length_mm", "body length (default: 12 mm, or L + 2 mm if longer, at W = 3 mm; "
        "scaled with W)")
    chamber_offset_mm: float | None = mm(  # type: ignore[assignment]
        "chamber_offset_mm", "clamped end to chamber start (default: centred)")
    body_material: MaterialRef = Field(
        "pdms_1_10", description="body (layer A): a preset id (GET /v1/materials) or inline")
    membrane_material: MaterialRef = Field(
        "ecoflex_00_30", description="membrane (layer B): a preset id or inline")

    def as_input(self) -> dict[str, object]:
        """Plain data for ``solver.design.design_from_dict``."""
        data = self.model_dump(exclude_none=True)
        return data


_SOLVER = SolverSettings()  # omitted settings keep the solver's defaults


class SolveSettingsIn(Schema):
    """The solver settings a client may choose; the rest keep ``SolverSettings``' defaults."""

    model_config = ConfigDict(json_schema_extra={"examples": [
        {"mesh_level": 1, "element": "hex2", "max_angle_deg": 90}]})

    mesh_level: int = Field(_SOLVER.mesh_level, ge=0, le=MAX_MESH_LEVEL,
                            description="0 = coarsest")
    mesh_divisions: Literal[MESH_DIVISIONS] = Field(  # type: ignore[assignment,valid-type]
        _SOLVER.mesh_divisions,
        description="level-0 resolution: balanced (the default and the database's: end "
                    "walls graded to the chamber, two chamber layers; within 2 % in angle), "
                    "former (the default before it, 2.3-2.9 % low in angle) or fine_x "
                    "(twice the former's x divisions, ~2x the solve time)")
    element: Literal["hex2", "hex1"] = _SOLVER.element  # type: ignore[assignment]
    control: Literal["volume", "pressure"] = _SOLVER.control  # type: ignore[assignment]
    max_angle_deg: float = Field(_SOLVER.max_angle_deg, ge=0.1, le=360.0,
                                 description="stop angle, degrees")
    max_pressure_pa: float = Field(_SOLVER.max_pressure_pa, ge=1.0, le=1e7,
                                   description="stop pressure, Pa")
    max_volume_ul: float = Field(_SOLVER.max_volume_ul, ge=1e-3, le=1e4,
                                 description="stop volume, ul")
    tip: Literal["free", "spring", "blocked"] = _SOLVER.tip  # type: ignore[assignment]
    spring_k_n_per_m: float = Field(_SOLVER.spring_k_n_per_m, ge=0.0, le=1e6,
                                    description="tip spring stiffness (tip = spring), N/m")
