"""POST /v1/predict (angles with a band, by pressure, volume or time at a flow rate) and
GET /v1/predict/plot (the same as a PNG: against pressure, or against time)."""

from __future__ import annotations

from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter, Query
from fastapi.responses import Response
from pydantic_core import to_json

from service.convert import DESIGN_LOCS, to_design
from service.deps import ModelsDep, SettingsDep
from service.errors import FieldError, located
from service.pump import FLOW_RANGE
from service.schemas import PlotQuery, PredictRequest, PredictResponse
from solver.errors import InputError

router = APIRouter(prefix="/v1", tags=["predict"])

PNG: dict[int | str, dict[str, Any]] = {
    200: {"content": {"image/png": {}}, "description": "the plot, PNG"}}


def inlet_of(inlet: Any) -> Any:
    """The schema's InletIn as a ``surrogate.hydraulics.Inlet`` (None stays None)."""
    from surrogate.hydraulics import Inlet

    return None if inlet is None else Inlet(**inlet.model_dump())


@router.post("/predict", response_model=PredictResponse,
             summary="Angle against pressure, injected volume, or time at a flow rate, "
                     "with a prediction band and validity flags")
async def predict(request: PredictRequest, models: ModelsDep) -> Response:
    """Angles (degrees) with their band from the chosen model, asked at pressures (Pa),
    injected volumes (ul) or times (s) at a flow rate (ul/s): service/pump.py.

    Runs on the event loop: the model evaluation takes about 0.1 ms, less than a
    thread-pool hand-off (benchmarks/bench_service.py)."""
    from service.pump import PumpQuestion, predict_answer

    design = to_design(request.design)
    surrogate = models.get(request.model)
    try:
        question = PumpQuestion(request.pressures_pa, request.volumes_ul, request.times_s,
                                request.flow_ul_s, inlet_of(request.inlet),
                                request.pressures_at)
        body = predict_answer(surrogate, design, question, request.model, request.level)
    except InputError as exc:  # e.g. OutOfFamilyError / OutOfBoxError (a design field)
        raise located(exc, ("body",), DESIGN_LOCS) from None
    # plain JSON of plain data: the schema is PredictResponse (response_model, for the docs)
    return Response(to_json(body), media_type="application/json")


@router.get("/predict/plot", response_class=Response, responses=PNG,
            summary="PNG of the predicted curve, its band, nearby FE curves and measurements; "
                    "against pressure, or against time at flow_ul_s with the pressure")
def predict_plot(query: Annotated[PlotQuery, Query()], models: ModelsDep,
                 settings: SettingsDep) -> Response:
    from service.plotting import nearby_curves, plot_in_time, plot_prediction
    from service.pump import PumpQuestion, predict_answer
    from surrogate.hydraulics import Inlet

    if len(query.measured_pressure_pa) != len(query.measured_angle_deg):
        raise FieldError(("query", "measured_angle_deg"),
                         f"{len(query.measured_angle_deg)} angles for "
                         f"{len(query.measured_pressure_pa)} pressures",
                         "as many measured_angle_deg as measured_pressure_pa")
    if query.flow_ul_s is not None and query.measured_pressure_pa:
        raise FieldError(("query", "measured_pressure_pa"), "measured points by pressure "
                         "are drawn on the pressure plot", "no measured points with flow_ul_s")
    if query.inlet and query.flow_ul_s is None:
        raise FieldError(("query", "flow_ul_s"), "the inlet's pressure drop R Q needs the "
                         "flow rate", f"{FLOW_RANGE} with inlet")
    # an axis's end given for the other axis is refused, not ignored: ?t_max_s=30 alone
    # drew the pressure plot to 2000 Pa (the audit of the forty-first session)
    given = query.model_fields_set
    if "t_max_s" in given and query.flow_ul_s is None:
        raise FieldError(("query", "t_max_s"), "the time axis needs the pump's flow rate",
                         f"{FLOW_RANGE} with t_max_s; p_max_pa for the pressure axis")
    if "p_max_pa" in given and query.flow_ul_s is not None:
        raise FieldError(("query", "p_max_pa"), "with flow_ul_s the plot is against time",
                         "t_max_s with flow_ul_s; p_max_pa without it")
    design = to_design(query.model_dump(include={"L_mm", "t_mm", "T_mm", "b_mm", "h_mm",
                                                 "W_mm", "body_material",
                                                 "membrane_material"}),
                       loc=("query",))
    surrogate = models.get(query.model)
    if query.flow_ul_s is None:
        question = PumpQuestion(pressures_pa=np.linspace(0.0, query.p_max_pa, 101).tolist())
    else:
        question = PumpQuestion(times_s=np.linspace(0.0, query.t_max_s, 101).tolist(),
                                flow_ul_s=query.flow_ul_s,
                                inlet=Inlet() if query.inlet else None)
    try:
        prediction = predict_answer(surrogate, design, question, query.model, query.level)
    except InputError as exc:
        # the plot asks its own pressures or times: a refusal of those names the query's
        # parameter that chose them (p_max_pa; flow_ul_s for the time axis), and what it
        # allows in the plot's terms: a model that answers by pressure only is offered
        # the pressure plot, not /v1/predict's pressures_pa
        if exc.allowed and exc.allowed.startswith("pressures_pa"):
            exc = InputError(exc.field, exc.detail, "the plot against pressure (p_max_pa, "
                             "without flow_ul_s)" + exc.allowed[len("pressures_pa"):],
                             allowed_said=exc.allowed_said)
        raise located(exc, ("query",), {"pressures_pa": ("p_max_pa",),
                                        "times_s": ("flow_ul_s",)}) from None
    if query.flow_ul_s is None:
        fe = nearby_curves(settings.db_path, design, query.nearby, query.p_max_pa)
        png = plot_prediction(prediction, fe, query.measured_pressure_pa,
                              query.measured_angle_deg)
    else:
        fe = nearby_curves(settings.db_path, design, query.nearby, query.t_max_s,
                           query.flow_ul_s)
        png = plot_in_time(prediction, fe)
    return Response(png, media_type="image/png")
