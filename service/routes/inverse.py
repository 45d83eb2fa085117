"""POST /v1/inverse: the pressure (with its band) at which a design reaches a target angle."""

from __future__ import annotations

from fastapi import APIRouter

from service.convert import jsonable, to_design
from service.deps import ModelsDep
from service.schemas import InverseRequest, InverseResponse

router = APIRouter(prefix="/v1", tags=["inverse"])


def _num(value: object) -> float | None:
    return jsonable(float(value)) if value is not None else None  # type: ignore[arg-type]


@router.post("/inverse", response_model=InverseResponse,
             summary="Pressure that gives a target angle, with its band")
def inverse(request: InverseRequest, models: ModelsDep) -> InverseResponse:
    design = to_design(request.design)
    surrogate = models.get(request.model)
    result = surrogate.inverse(design, request.target_angle_deg, level=request.level)
    return InverseResponse(model=request.model, level=request.level,
                           target_angle_deg=request.target_angle_deg, design=design.as_dict(),
                           pressure_pa=_num(result.pressure_pa), lower_pa=_num(result.lower_pa),
                           upper_pa=_num(result.upper_pa),
                           validity=jsonable(dict(result.validity)))
