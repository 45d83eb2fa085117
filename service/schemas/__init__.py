"""Request and response schemas of the HTTP API (one schema per use).

The HTTP layer converts between these and the domain objects (``Design``,
``SolverSettings``, the surrogate's ``Prediction``); limits live in ``Field(...)``
and are registered in ``service.errors.FIELD_RANGES`` so that every validation
error states the allowed range.
"""

from service.errors import FIELD_FORMS, FIELD_RANGES
from service.schemas._ranges import field_ranges
from service.schemas.common import (
    DesignIn,
    MaterialIn,
    Schema,
    SolveSettingsIn,
    text_forms,
)
from service.schemas.curves import CurveDetail, CurvePage, CurvesQuery, CurveSummary
from service.schemas.health import Health
from service.schemas.inverse import (
    PAIR_FORMS,
    InverseRequest,
    InverseResponse,
    MaterialPair,
    PressureRequest,
    PressureResponse,
    TargetIn,
)
from service.schemas.jobs import Job, SolveRequest
from service.schemas.materials import Material, MaterialList
from service.schemas.predict import InletIn, PlotQuery, PredictRequest, PredictResponse

REQUEST_MODELS = (DesignIn, MaterialIn, SolveSettingsIn, CurvesQuery, InverseRequest, TargetIn,
                  MaterialPair, PressureRequest, SolveRequest, PlotQuery, PredictRequest,
                  InletIn)
FIELD_RANGES.update(field_ranges(REQUEST_MODELS))
FIELD_FORMS.update(text_forms(), **{"material_pairs.*": PAIR_FORMS})

__all__ = [
    "REQUEST_MODELS", "CurveDetail", "CurvePage", "CurveSummary", "CurvesQuery", "DesignIn",
    "Health", "InletIn", "InverseRequest", "InverseResponse", "Job", "Material", "MaterialIn",
    "MaterialList", "MaterialPair", "PlotQuery", "PredictRequest", "PredictResponse",
    "PressureRequest", "PressureResponse", "Schema", "SolveRequest", "SolveSettingsIn",
    "TargetIn",
]
