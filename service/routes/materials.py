"""GET /v1/materials: the preset Ogden materials (Table 1 of the paper)."""

from __future__ import annotations

from fastapi import APIRouter

from service.schemas import Material, MaterialList
from solver.materials import MATERIALS

router = APIRouter(prefix="/v1", tags=["materials"])


@router.get("/materials", response_model=MaterialList, summary="Preset materials")
async def materials() -> MaterialList:
    return MaterialList(items=[
        Material(id=m.id, mu_kpa=list(m.mu_kpa), alpha=list(m.alpha), mu0_kpa=m.mu0_kpa)
        for m in MATERIALS.values()])
