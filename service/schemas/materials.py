"""GET /v1/materials: the preset Ogden materials."""

from __future__ import annotations

from pydantic import BaseModel, Field


class Material(BaseModel):
    id: str
    mu_kpa: list[float] = Field(description="Ogden moduli, kPa")
    alpha: list[float] = Field(description="Ogden exponents")
    mu0_kpa: float = Field(description="initial shear modulus sum(mu*alpha)/2, kPa")


class MaterialList(BaseModel):
    items: list[Material]
    note: str = ("A design may name a preset id or give a material inline as "
                 "{id, mu_kpa: [...], alpha: [...]}.")
