"""POST /v1/inverse (designs that meet a target, ranked) and POST /v1/inverse/pressure
(the pressure, with its band, at which one design reaches given angles)."""

from __future__ import annotations

import threading
from typing import Any

from fastapi import APIRouter, Request

from service.convert import DESIGN_LOCS, jsonable, to_design
from service.deps import ModelsDep
from service.disconnect import unless_disconnected
from service.errors import located
from service.models import require
from service.schemas import InverseRequest, InverseResponse, PressureRequest, PressureResponse
from solver.errors import InputError

router = APIRouter(prefix="/v1", tags=["inverse"])

# surrogate field name -> path in the request body
DESIGN_FIELDS: dict[str, tuple[str | int, ...]] = {
    "pressure_pa": ("target", "pressure_pa"), "angle_deg": ("target", "angle_deg"),
    "force_mn": ("target", "force_mn"), "kind": ("target", "kind"),
    "volume_ul": ("target", "volume_ul"), "time_s": ("target", "time_s"),
    "flow_ul_s": ("target", "flow_ul_s"),
    "L_mm": ("L_bounds_mm",), "t_mm": ("t_bounds_mm",), "T_mm": ("T_bounds_mm",),
    "b_mm": ("b_bounds_mm",), "h_mm": ("h_bounds_mm",), "target": ("target",),
    "body_stiffness_scale": ("body_stiffness_scale_bounds",),
    "membrane_stiffness_scale": ("membrane_stiffness_scale_bounds",),
    "material_pairs": ("material_pairs",),
}
PRESSURE_FIELDS: dict[str, tuple[str | int, ...]] = {**DESIGN_LOCS, "angle_deg": ("angles_deg",)}


def _pair(values: list[float] | None) -> tuple[float, float] | None:
    return (values[0], values[1]) if values else None


@router.post("/inverse", response_model=InverseResponse,
             summary="Designs that meet a target, ranked; or why none can")
async def inverse(request: InverseRequest, models: ModelsDep, http: Request
                  ) -> InverseResponse:
    """Searches L, t, T, b, h (and the stiffness scales when bounded) within the bounds,
    for every allowed material pair the model covers (surrogate.search.design_search). The
    search stops soon after its client disconnects (service.disconnect)."""
    return await unless_disconnected(http, lambda cancel: _search(request, models, cancel))


def _search(request: InverseRequest, models: Any, cancel: threading.Event) -> InverseResponse:
    from surrogate import DesignTarget
    from surrogate.search.design_search import SearchBounds, search_designs

    model = models.get(request.model)
    if not (hasattr(model, "evaluate_designs") or hasattr(model, "covered_slices")):
        require(model, request.model, "covered_slices")   # 422: this model cannot search
    t = request.target
    pairs = (tuple((p.body_material, p.membrane_material) for p in request.material_pairs)
             if request.material_pairs else None)
    try:
        result = search_designs(
            model, DesignTarget(t.kind, t.pressure_pa, t.angle_deg, t.force_mn, t.volume_ul,
                                t.time_s, t.flow_ul_s),
            SearchBounds(L_mm=_pair(request.L_bounds_mm), t_mm=_pair(request.t_bounds_mm),
                         T_mm=_pair(request.T_bounds_mm), b_mm=_pair(request.b_bounds_mm),
                         h_mm=_pair(request.h_bounds_mm),
                         body_stiffness_scale=_pair(request.body_stiffness_scale_bounds),
                         membrane_stiffness_scale=_pair(
                             request.membrane_stiffness_scale_bounds),
                         pairs=pairs),
            objective=request.objective, n_results=request.n_results, level=request.level,
            cancel=cancel)
    except InputError as exc:
        raise located(exc, ("body",), DESIGN_FIELDS) from None
    out = jsonable(result.as_dict())
    return InverseResponse(model=request.model, level=request.level,
                           objective=out["objective"], feasible=out["feasible"],
                           explanation=out["explanation"], candidates=out["candidates"],
                           best_reachable=out["best_reachable"],
                           n_evaluated=out["n_evaluated"])


@router.post("/inverse/pressure", response_model=PressureResponse,
             summary="Pressure, injected volume and time at a flow rate that give each "
                     "target angle for one design, with bands")
def inverse_pressure(request: PressureRequest, models: ModelsDep) -> PressureResponse:
    from service.pump import inverse_answer
    from service.routes.predict import inlet_of

    design = to_design(request.design)
    surrogate = require(models.get(request.model), request.model, "inverse")
    try:
        body = inverse_answer(surrogate, design, request.angles_deg, request.model,
                              request.level, request.flow_ul_s, inlet_of(request.inlet))
    except InputError as exc:
        raise located(exc, ("body",), PRESSURE_FIELDS) from None
    return PressureResponse(**body)
