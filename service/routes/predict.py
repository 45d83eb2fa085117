"""POST /v1/predict (angles with a band) and GET /v1/predict/plot (the same as a PNG)."""

from __future__ import annotations

from typing import Annotated, Any

import numpy as np
from fastapi import APIRouter, Query
from fastapi.responses import Response
from pydantic_core import to_json

from service.convert import prediction_body, to_design
from service.deps import ModelsDep, SettingsDep
from service.errors import FieldError, located
from service.schemas import PlotQuery, PredictRequest, PredictResponse
from solver.errors import InputError

router = APIRouter(prefix="/v1", tags=["predict"])

PNG: dict[int | str, dict[str, Any]] = {
    200: {"content": {"image/png": {}}, "description": "the plot, PNG"}}


def predict_dict(surrogate: Any, design: Any, pressures_pa: Any, level: float,
                 model: str, loc: tuple[str, ...] = ("body",)) -> dict[str, Any]:
    """Run the model and convert its Prediction to the response's plain data."""
    try:
        p = surrogate.predict(design, np.asarray(pressures_pa, float), level=level)
    except InputError as exc:  # e.g. OutOfFamilyError / OutOfBoxError (field "design")
        raise located(exc, loc) from None
    return prediction_body(p, model, level, design)


@router.post("/predict", response_model=PredictResponse,
             summary="Angle against pressure, with a prediction band and validity flags")
async def predict(request: PredictRequest, models: ModelsDep) -> Response:
    """Angles (degrees) at the given pressures (Pa) from the chosen surrogate model.

    Runs on the event loop: the model evaluation takes about 0.1 ms, less than a
    thread-pool hand-off (benchmarks/bench_service.py)."""
    given = [n for n in ("pressures_pa", "volumes_ul", "times_s")
             if getattr(request, n) is not None]
    if len(given) != 1:
        raise FieldError(("body", given[1] if given else "pressures_pa"),
                         f"give exactly one of pressures_pa, volumes_ul, or times_s; got "
                         f"{', '.join(given) or 'none'}",
                         "each 0 <= pressures_pa <= 20000 (Pa); or volumes_ul (ul); or "
                         "times_s (s) with flow_ul_s (ul/s)")
    if (request.times_s is None) != (request.flow_ul_s is None):
        raise FieldError(("body", "flow_ul_s"), "times_s and flow_ul_s go together",
                         "0 < flow_ul_s <= 1000 (ul/s) with times_s")
    design = to_design(request.design)
    surrogate = models.get(request.model)
    if request.pressures_pa is not None:
        body = predict_dict(surrogate, design, request.pressures_pa, request.level,
                            request.model)
    else:
        volumes = (np.asarray(request.volumes_ul, float) if request.volumes_ul is not None
                   else np.asarray(request.times_s, float) * float(request.flow_ul_s or 0))
        by_volume = getattr(surrogate, "predict_volume", None)
        if by_volume is None:
            raise FieldError(("body", "volumes_ul" if request.volumes_ul else "times_s"),
                             f"model {request.model!r} answers by pressure only",
                             'model "emulator" for volumes and times')
        try:
            p = by_volume(design, volumes, level=request.level)
        except InputError as exc:
            raise located(exc, ("body",)) from None
        body = prediction_body(p, request.model, request.level, design)
        if request.times_s is not None:
            body["time_s"] = [float(t) for t in request.times_s]
    # plain JSON of plain data: the schema is PredictResponse (response_model, for the docs)
    return Response(to_json(body), media_type="application/json")


@router.get("/predict/plot", response_class=Response, responses=PNG,
            summary="PNG of the predicted curve, its band, nearby FE curves and measurements")
def predict_plot(query: Annotated[PlotQuery, Query()], models: ModelsDep,
                 settings: SettingsDep) -> Response:
    from service.plotting import nearby_curves, plot_prediction

    if len(query.measured_pressure_pa) != len(query.measured_angle_deg):
        raise FieldError(("query", "measured_angle_deg"),
                         f"{len(query.measured_angle_deg)} angles for "
                         f"{len(query.measured_pressure_pa)} pressures",
                         "as many measured_angle_deg as measured_pressure_pa")
    design = to_design(query.model_dump(include={"L_mm", "t_mm", "T_mm", "b_mm", "h_mm",
                                                 "body_material", "membrane_material"}),
                       loc=("query",))
    surrogate = models.get(query.model)
    pressures = np.linspace(0.0, query.p_max_pa, 101)
    prediction = predict_dict(surrogate, design, pressures, query.level, query.model,
                              loc=("query",))
    fe = nearby_curves(settings.db_path, design, query.nearby, query.p_max_pa)
    png = plot_prediction(prediction, fe, query.measured_pressure_pa, query.measured_angle_deg)
    return Response(png, media_type="image/png")
