"""The published contract (/openapi.json): FastAPI's schema plus what it cannot infer.

- Every error status each operation can answer is documented as
  ``application/problem+json`` with the ``Problem`` schema (RFC 9457; the mapping from
  errors to statuses is ``service.errors``). FastAPI's own 422 (``HTTPValidationError``,
  ``application/json``) is replaced: the server never sends it.
- ``POST /v1/calibrate`` needs the API key only to ``save``: its security is optional
  (``[{}, {"APIKeyHeader": []}]``), as it behaves.
- 401 documents ``WWW-Authenticate``, 415 ``Accept-Encoding``, 503 ``Retry-After``.
"""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI
from fastapi.openapi.utils import get_openapi
from pydantic import BaseModel, Field

PROBLEM_JSON = "application/problem+json"


class ProblemItem(BaseModel):
    loc: list[str | int] = Field(description="where in the request: body, query or path, "
                                 "then the field path")
    field: str = Field(description="the field, dotted (design.t_mm)")
    message: str
    allowed: str | None = Field(None, description="the allowed range or values, in words")


class Problem(BaseModel):
    """An RFC 9457 problem document: every error answer of this service."""

    type: str = Field(description="urn:balloon:problem:<kind>, e.g. invalid-input")
    title: str
    status: int = Field(description="the HTTP status, repeated")
    detail: str = Field(description="what was wrong and what to do, in one sentence")
    instance: str = Field(description="the request path")
    errors: list[ProblemItem] | None = Field(None, description="one per invalid field")
    nearest_design: dict[str, Any] | None = Field(
        None, description="a design outside the model's box (urn:balloon:problem:out-of-box): "
        "the nearest design inside it as a request's design takes it (L_mm, t_mm, T_mm, "
        "b_mm, h_mm, W_mm; each layer by id, a scaled preset as <preset>*<s>)")


STATUS_WORDS = {
    401: "no API key in X-API-Key", 403: "wrong API key, or the server has none",
    404: "not found (record, job, model)", 409: "conflicts with stored state",
    413: "request body over the limit",
    415: "request body in a content coding (gzip): send it uncompressed",
    422: "invalid input: the fields and allowed ranges",
    503: "a server resource is unavailable (no or damaged database, no fitted surrogate, a "
         "damaged saved model, a full job queue); Retry-After when worth retrying",
}

# Error statuses per operation, as the server answers them (tests/test_service_contract.py).
BODY = (413, 415, 422)
OPERATION_ERRORS: dict[tuple[str, str], tuple[int, ...]] = {
    ("get", "/v1/health"): (),
    ("get", "/v1/materials"): (),
    ("get", "/v1/effects"): (),
    ("post", "/v1/predict"): (*BODY, 404, 503),
    ("get", "/v1/predict/plot"): (422, 404, 503),
    ("post", "/v1/inverse"): (*BODY, 404, 503),
    ("post", "/v1/inverse/pressure"): (*BODY, 404, 503),
    ("get", "/v1/curves"): (422, 503),
    ("get", "/v1/curves/{curve_id}"): (404, 503),
    ("post", "/v1/solve"): (*BODY, 401, 403, 409, 503),
    ("get", "/v1/jobs/{job_id}"): (404,),
    ("delete", "/v1/jobs/{job_id}"): (401, 403, 404, 409),
    ("post", "/v1/calibrate"): (*BODY, 401, 403, 404, 409, 503),
}
HEADERS = {
    401: {"WWW-Authenticate": {"description": "APIKey header=\"X-API-Key\"",
                               "schema": {"type": "string"}}},
    415: {"Accept-Encoding": {"description": "identity: the only content coding taken",
                               "schema": {"type": "string"}}},
    503: {"Retry-After": {"description": "seconds to wait before retrying (when known)",
                          "schema": {"type": "integer"}}},
}


def contract(app: FastAPI) -> dict[str, Any]:
    """The OpenAPI document of ``app`` (built once, then cached on the app)."""
    if app.openapi_schema:
        return app.openapi_schema
    spec = get_openapi(title=app.title, version=app.version, description=app.description,
                       routes=app.routes)
    schemas = spec.setdefault("components", {}).setdefault("schemas", {})
    problem = Problem.model_json_schema(ref_template="#/components/schemas/{model}")
    schemas.update(problem.pop("$defs"))
    schemas["Problem"] = problem
    for name in ("HTTPValidationError", "ValidationError"):
        schemas.pop(name, None)
    ref = {"$ref": "#/components/schemas/Problem"}
    for path, operations in spec["paths"].items():
        for method, op in operations.items():
            responses = op["responses"]
            responses.pop("422", None)
            for status in OPERATION_ERRORS.get((method, path), (422,)):
                entry: dict[str, Any] = {"description": STATUS_WORDS[status],
                                         "content": {PROBLEM_JSON: {"schema": ref}}}
                if status in HEADERS:
                    entry["headers"] = HEADERS[status]
                responses[str(status)] = entry
    calibrate = spec["paths"]["/v1/calibrate"]["post"]
    calibrate["security"] = [{}, {"APIKeyHeader": []}]  # the key only to save
    app.openapi_schema = spec
    return spec


def install_contract(app: FastAPI) -> None:
    app.openapi = lambda: contract(app)  # type: ignore[method-assign]
