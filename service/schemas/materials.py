"""GET /v1/materials: the preset Ogden materials, and the stiffness scales a design may
state (a preset with every mu x s: ``<preset>*<s>`` or inline)."""

from __future__ import annotations

from pydantic import BaseModel, Field

from solver.design_space import (
    REDUCED_RATIO_RANGE,
    STIFFNESS_SCALE_LIMITS,
    STIFFNESS_SCALE_RANGE,
)


class Material(BaseModel):
    id: str
    mu_kpa: list[float] = Field(description="Ogden moduli, kPa")
    alpha: list[float] = Field(description="Ogden exponents")
    mu0_kpa: float = Field(description="initial shear modulus sum(mu*alpha)/2, kPa")


class StiffnessScales(BaseModel):
    """What the emulator answers of a layer stiffness-scaled by s (mu = s x the preset's),
    read from the one table, ``solver.design_space``: scaling both layers by one factor
    scales only the pressure axis, so each layer takes a wide range and only the ratio
    is bounded by the box."""

    layer: list[float] = Field(list(STIFFNESS_SCALE_LIMITS), description="[low, high] of "
                               "each layer's own s (body and membrane alike)")
    ratio: list[float] = Field(list(REDUCED_RATIO_RANGE), description="[low, high] of "
                               "s_body / s_membrane, the one the curve's shape depends on")
    search: list[float] = Field(list(STIFFNESS_SCALE_RANGE), description="[low, high] of "
                                "each layer's s that the design search (POST /v1/inverse) "
                                "ranges over")


class MaterialList(BaseModel):
    items: list[Material]
    stiffness_scale: StiffnessScales = Field(default_factory=StiffnessScales)
    note: str = ("A design may name a preset id or give a material inline as "
                 "{id, mu_kpa: [...], alpha: [...]}; a preset with every mu scaled by s as "
                 "<preset>*<s> (stiffness_scale: the s it may take).")
