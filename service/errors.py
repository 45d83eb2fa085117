"""Errors of the HTTP layer, and the ONE place where every error becomes an HTTP answer.

Every error answer is ``application/problem+json`` (RFC 9457)::

    {"type": "urn:balloon:problem:invalid-input", "title": "Invalid input", "status": 422,
     "detail": "...", "instance": "/v1/predict",
     "errors": [{"loc": ["body", "design", "t_mm"], "field": "design.t_mm",
                 "message": "...", "allowed": "0.05 <= t_mm <= 5"}]}

Mapping (domain class -> status):

    InputError, OutOfFamilyError, request validation   422
    NotFoundError (record, job, model, material)        404
    AuthError                                           401 (no key) / 403 (wrong or disabled)
    ConflictError, ExistsError (a saved model's name)    409
    PayloadTooLargeError                                413
    QueueFullError, UnavailableError                    503 with Retry-After
    Cancelled (the client disconnected; nobody reads it) 499, as proxies log it
    SolverError, any other BalloonError                 422
    anything unexpected                                 500, logged; no stack trace is sent
"""

from __future__ import annotations

import difflib
import logging
import re
from dataclasses import dataclass, field
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException as StarletteHTTPException

from solver.errors import BalloonError, ExistsError, InputError, NotFoundError, SolverError
from solver.plain_text import escaped
from surrogate.errors import Cancelled

log = logging.getLogger("balloon.service")

PROBLEM_JSON = "application/problem+json"


class ServiceError(BalloonError):
    """Base of the HTTP layer's own errors."""


class AuthError(ServiceError):
    """The API key is missing (``status=401``), wrong or not configured (403)."""

    def __init__(self, message: str, status: int = 401) -> None:
        super().__init__(message)
        self.status = status


class ConflictError(ServiceError):
    """The request conflicts with the current state (a finished job, a stored design)."""

    def __init__(self, message: str, **extra: Any) -> None:
        super().__init__(message)
        self.extra = extra


class PayloadTooLargeError(ServiceError):
    """The request body exceeds ``max_body_bytes``."""


class UnavailableError(ServiceError):
    """A resource the request needs is not available now (no surrogate, busy database)."""

    def __init__(self, message: str, retry_after_s: int | None = None) -> None:
        super().__init__(message)
        self.retry_after_s = retry_after_s


class QueueFullError(UnavailableError):
    """The solve queue is full; retry after ``retry_after_s`` seconds."""


class FieldError(InputError):
    """An InputError located in the request: ``loc`` is the full path, e.g.
    ``("body", "design", "t_mm")``; ``others`` are further fields of the same refusal
    (a design outside the box in several lengths), each a FieldError; ``nearest``: an
    out-of-box refusal's nearest design inside the box (a ``solver.design.Design``);
    ``design_refused``: the design itself is refused (its geometry or a material, as
    ``service.convert.to_design`` checks it), so an FE solve of it is refused the same way:
    the problem says ``"fe_solvable": false`` (a model's refusal, such as out-of-box,
    leaves the FE solve open)."""

    def __init__(self, loc: tuple[str | int, ...], message: str,
                 allowed: str | None = None, kind: str = "invalid-input",
                 others: tuple[FieldError, ...] = (), allowed_said: bool = False,
                 nearest: Any = None, design_refused: bool = False) -> None:
        super().__init__(".".join(str(p) for p in loc[1:]) or str(loc[0]), message, allowed,
                         allowed_said=allowed_said)
        self.loc = loc
        self.kind = kind
        self.others = others
        self.nearest = nearest
        self.design_refused = design_refused


def located(exc: InputError, prefix: tuple[str | int, ...],
            rename: dict[str, tuple[str | int, ...]] | None = None) -> FieldError:
    """Attach a request location to a domain InputError (``exc.field`` may be dotted).
    ``rename`` maps a domain field name to its path under ``prefix``."""
    if isinstance(exc, FieldError):
        return exc
    parts: tuple[str | int, ...] = tuple(exc.field.split(".")) if exc.field else ()
    if rename and exc.field in rename:
        parts = rename[exc.field]
    kind = "invalid-input" if type(exc) is InputError else _kebab(type(exc).__name__)
    others = tuple(located(o, prefix, rename) for o in getattr(exc, "others", ()))
    return FieldError(prefix + parts, exc.detail, exc.allowed, kind, others,
                      allowed_said=exc.allowed_said, nearest=getattr(exc, "nearest", None))


#: characters of a request's path a problem echoes as its ``instance``
LONGEST_INSTANCE = 1000


def instance_of(path: str) -> str:
    """A request's path as its problem's ``instance``, cut at LONGEST_INSTANCE characters
    (a 404 for a path of 100,000 characters echoed it whole, a 100 kB answer)."""
    return path if len(path) <= LONGEST_INSTANCE else f"{path[:LONGEST_INSTANCE]}..."


@dataclass
class Problem:
    """An RFC 9457 problem document."""

    status: int
    title: str
    detail: str
    kind: str
    errors: list[dict[str, Any]] = field(default_factory=list)
    headers: dict[str, str] = field(default_factory=dict)
    extra: dict[str, Any] = field(default_factory=dict)

    def response(self, request: Request) -> JSONResponse:
        body: dict[str, Any] = {"type": f"urn:balloon:problem:{self.kind}", "title": self.title,
                                "status": self.status, "detail": self.detail,
                                "instance": instance_of(request.url.path)}
        if self.errors:
            body["errors"] = self.errors
        body.update(self.extra)
        return JSONResponse(_shown(body), status_code=self.status, headers=self.headers,
                            media_type=PROBLEM_JSON)


def _shown(value: Any) -> Any:
    """A problem's every text with the characters a terminal or a page would obey
    escaped (``solver.plain_text.escaped``): a JSON key the request made up, echoed in
    detail, loc and field, held a bidi override or a C1 control raw (JSON escapes only
    U+0000-U+001F)."""
    if isinstance(value, str):
        return escaped(value)
    if isinstance(value, dict):
        return {_shown(k): _shown(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_shown(v) for v in value]
    return value


def problem_for(exc: BaseException) -> Problem:
    """The problem document of a domain or service error (the mapping table above)."""
    if isinstance(exc, QueueFullError | UnavailableError):
        headers = {"Retry-After": str(exc.retry_after_s)} if exc.retry_after_s else {}
        kind = "queue-full" if isinstance(exc, QueueFullError) else "unavailable"
        return Problem(503, "Service unavailable", str(exc), kind, headers=headers)
    if isinstance(exc, AuthError):
        headers = {"WWW-Authenticate": 'APIKey header="X-API-Key"'} if exc.status == 401 else {}
        return Problem(exc.status, "Not authorised", str(exc), "unauthorised", headers=headers)
    if isinstance(exc, ConflictError):
        return Problem(409, "Conflict", str(exc), "conflict", extra=exc.extra)
    if isinstance(exc, ExistsError):  # before InputError: a taken name is a conflict
        return Problem(409, "Conflict", str(exc), "conflict")
    if isinstance(exc, PayloadTooLargeError):
        return Problem(413, "Request body too large", str(exc), "payload-too-large")
    if isinstance(exc, InputError):
        kind = getattr(exc, "kind", None) or (
            "invalid-input" if type(exc) is InputError else _kebab(type(exc).__name__))
        errors = [_error_entry(e) for e in (exc, *getattr(exc, "others", ()))]
        nearest = getattr(exc, "nearest", None)
        extra = {} if nearest is None else {"nearest_design": _nearest_design(nearest)}
        if getattr(exc, "design_refused", False):
            extra["fe_solvable"] = False
        return Problem(422, "Invalid input", str(exc), kind, errors=errors, extra=extra)
    if isinstance(exc, NotFoundError):
        return Problem(404, "Not found", str(exc), "not-found")
    if isinstance(exc, SolverError):
        return Problem(422, "Solver error", str(exc), "solver-error")
    if isinstance(exc, Cancelled):  # the work stopped because its client left (the log's)
        return Problem(499, "Client closed request", str(exc), "client-closed-request")
    if isinstance(exc, BalloonError):  # e.g. the surrogate's OutOfFamilyError
        return Problem(422, "Cannot answer for this input", str(exc),
                       _kebab(type(exc).__name__))
    return Problem(500, "Internal server error",
                   "an unexpected error occurred; it has been logged", "internal")


def _error_entry(exc: InputError) -> dict[str, Any]:
    """One entry of a problem's ``errors``: where, which field, what, the allowed range."""
    loc: list[str | int] = list(exc.loc) if isinstance(exc, FieldError) else [exc.field]
    error: dict[str, Any] = {"loc": loc, "field": exc.field, "message": exc.detail}
    if exc.allowed:
        error["allowed"] = exc.allowed
    return error


def _nearest_design(design: Any) -> dict[str, Any]:
    """An out-of-box refusal's nearest design inside the box as a request takes it: the
    lengths (mm) and each layer by id (a scaled preset ``pdms_1_10*2``), so that a client
    can ask it instead (the explorer's "Load the nearest design")."""
    lengths = {n: getattr(design, n) for n in ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "W_mm")}
    return {**lengths, "body_material": design.body_material.id,
            "membrane_material": design.membrane_material.id}


def _kebab(name: str) -> str:
    out = "".join("-" + c.lower() if c.isupper() else c for c in name).lstrip("-")
    return out.removesuffix("-error") or "error"


BODY_NOT_PARSED = "There was an error parsing the body"  # FastAPI's words for its 400

# Field name -> allowed range in words, filled by service.schemas from the Field limits.
FIELD_RANGES: dict[str, str] = {}
# Text field name -> the form its pattern allows, in words (service.schemas fills it): a
# value not of that form is told this, not the regular expression.
FIELD_FORMS: dict[str, str] = {}


def field_range(loc: list[str | int] | tuple[str | int, ...]) -> str | None:
    """The allowed range in words of the request field at ``loc`` (``("body", "design",
    "L_mm")``; a list's item by its list), from FIELD_RANGES. A measured row's column
    (/v1/calibrate's rows) is not the request field of that name elsewhere (its
    pressure_pa is not a target's): what any cell may hold (``rows.*.*``); a row, what a
    row is (``rows.*``); the rows, how many (``rows``: a cell's words were said for
    ``"rows": {}`` and ``"rows": []``)."""
    names = [p for p in loc[1:] if isinstance(p, str)]
    if "rows" in loc[1:2]:
        return FIELD_RANGES.get("rows" + ".*" * min(len(loc) - 2, 2))
    return FIELD_RANGES.get(_field_key(loc)) if names else None


def _field_key(loc: list[str | int] | tuple[str | int, ...]) -> str:
    """The name FIELD_RANGES and FIELD_FORMS hold a field at ``loc`` under: its own name,
    or ``list.*`` for an item of a list (``("body", "pressures_pa", 3)``: an item's range,
    not its list's number of values)."""
    names = [p for p in loc[1:] if isinstance(p, str)]
    return names[-1] + (".*" if isinstance(loc[-1], int) else "") if names else ""


# A material is a preset id (text) or an inline object (service.schemas.common.MaterialRef):
# pydantic tries both and reports each branch's error under its tag; the request has
# no field of that name. The tags -> whether the branch is the text one.
MATERIAL_BRANCHES = {"constrained-str": True, "MaterialIn": False}


def _branch(err: dict[str, Any]) -> tuple[int, bool] | None:
    """(index of the union tag in ``loc``, True for the text branch), or None."""
    for i, part in enumerate(err.get("loc", ())):
        if part in MATERIAL_BRANCHES:
            return i, MATERIAL_BRANCHES[part]
    return None


def _sent_kinds(errors: list[dict[str, Any]]) -> dict[tuple[Any, ...], str]:
    """Each failed material's location -> what was sent: "text", "object" or "other"
    (read off the text branch's error, whose input is the value as sent)."""
    kinds = {}
    for err in errors:
        found = _branch(err)
        if found and found[1]:
            value = err.get("input")
            kinds[tuple(err["loc"][:found[0]])] = (
                "text" if isinstance(value, str) else "object" if isinstance(value, dict)
                else "other")
    return kinds


def _one_branch(errors: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """A material's errors from the branch of what was sent, located at the field without
    the tag: text -> the id's error; an object -> its fields' errors; anything else (a
    number, null, a list) -> one error saying what a material is."""
    kinds = _sent_kinds(errors)
    out = []
    for err in errors:
        found = _branch(err)
        if found is None:
            out.append(err)
            continue
        i, text_branch = found
        field_loc = tuple(err["loc"][:i])
        kind = kinds.get(field_loc, "object")
        if kind == "other" and text_branch:
            out.append({**err, "loc": field_loc, "msg": "Input should be a material id "
                        "(text) or an inline material {id, mu_kpa, alpha}"})
        elif kind != "other" and text_branch == (kind == "text"):
            out.append({**err, "loc": field_loc + tuple(err["loc"][i + 1:])})
    return out


# fields a design does not take but a user may send, and how the request says them (the
# CLI spells the stiffness scales as options of their own)
EXTRA_HINTS = {
    "body_stiffness_scale": 'a stiffness scale is part of the material id: "body_material": '
                            '"pdms_1_10*1.2" (every mu of the preset x 1.2)',
    "membrane_stiffness_scale": 'a stiffness scale is part of the material id: '
                                '"membrane_material": "ecoflex_00_30*0.8" (every mu x 0.8)'}


def _sibling_fields(request: Request, loc: list[str | int]) -> list[str]:
    """The fields the object at ``loc[:-1]`` of the request's body takes (its query
    parameters for ``loc`` in the query), read off the published schema of the request's
    route ([] where it cannot be read): what an unknown field's "did you mean" is chosen
    from."""
    try:
        spec = request.app.openapi()
        template = request.scope["route"].path
        op = spec["paths"][template][request.method.lower()]
        if loc[0] == "query":       # the operation's query parameters
            return [p["name"] for p in op.get("parameters", ()) if p.get("in") == "query"]
        schema = op["requestBody"]["content"]["application/json"]["schema"]

        def resolve(sch: dict) -> dict:
            while "$ref" in sch:
                sch = spec["components"]["schemas"][sch["$ref"].rsplit("/", 1)[-1]]
            for option in sch.get("anyOf", ()):      # an optional object: its object form
                option = resolve(option)
                if "properties" in option or "items" in option:
                    return option
            return sch

        for part in loc[1:-1]:
            schema = resolve(schema)
            schema = schema["items"] if isinstance(part, int) else schema["properties"][part]
        return list(resolve(schema).get("properties", {}))
    except (KeyError, TypeError, AttributeError):
        return []


#: the entries of a 422's ``errors`` (and of its detail) listed; the rest counted. A 9 kB
#: body of 1000 unknown fields had a 296 kB answer, a 3 MB /v1/calibrate body with `true`
#: in each of 20,000 rows one of 9.6 MB
MAX_LISTED_ERRORS = 20


def _validation_errors(errors: list[dict[str, Any]], request: Request | None = None
                       ) -> list[dict[str, Any]]:
    out = []
    for err in errors:
        if err.get("type") == "json_invalid":
            # pydantic locates it at ("body", character offset): the body is the field
            out.append(_unparsed_body(f"cannot be parsed as JSON ("
                                      f"{(err.get('ctx') or {}).get('error', 'invalid')} at "
                                      f"character {err.get('loc', ('', '?'))[-1]})"))
            continue
        loc = [short_name(p) for p in err.get("loc", ()) if isinstance(p, str | int)]
        names = [p for p in loc[1:] if isinstance(p, str)]
        item: dict[str, Any] = {"loc": loc,
                                "field": ".".join(str(p) for p in loc[1:]) or str(loc[0]),
                                "message": str(err.get("msg", "invalid value"))}
        if err.get("type") == "value_error":     # a validator's own words, without
            item["message"] = str((err.get("ctx") or {}).get("error", item["message"]))
        allowed = field_range(loc)
        if isinstance(loc[-1], int) and _field_key(loc) in FIELD_FORMS:
            # an item of forms in words (a material pair: text or an object)
            allowed = FIELD_FORMS[_field_key(loc)]
        elif err.get("type") in OBJECT_TYPES:
            # an object was asked for: its fields, not the range of a field of that name
            # elsewhere (the plot's query `inlet` is true or false, the body's an object;
            # an item of `material_pairs` is not its list's "1-20 values")
            allowed = _allowed_by_kind(err, request, loc) or allowed
        if err.get("type") == "extra_forbidden":
            # a field this object does not take: no range of it (it is refused whatever its
            # value), the way to say it where there is one
            allowed = EXTRA_HINTS.get(names[-1] if names else "", "leave it out: this "
                                      "object does not take it (the schema at /docs)")
            fields = (_sibling_fields(request, loc) if request is not None and names
                      and names[-1] not in EXTRA_HINTS else [])
            # the field with its unit (L for L_mm), else the nearest spelling
            near = ([f for f in fields if f.startswith(names[-1] + "_")]
                    or difflib.get_close_matches(names[-1], fields, n=1, cutoff=0.6))
            if near:        # pressure_pa for pressures_pa, L for L_mm
                item["message"] += f" (did you mean {near[0]!r}?)"
        elif err.get("type") == "string_pattern_mismatch" and names and names[-1] in FIELD_FORMS:
            allowed = FIELD_FORMS[names[-1]]       # the form in words, not the pattern
            item["message"] = f"{short_input(err.get('input'))} is not of this form"
        elif not allowed and names:
            allowed = FIELD_FORMS.get(names[-1])   # a material that is a number, null, ...
        if not allowed:     # a choice of words, an object or the body: what it takes
            allowed = _allowed_by_kind(err, request, loc)
            if err.get("type") in ("literal_error", "enum"):    # the words: in allowed
                item["message"] = f"{short_input(err.get('input'))} is not one of these"
        if err.get("type") == QUERY_BOOL_ERROR:
            item["message"] = f"{short_input(err.get('input'))} is not one of these"
        if allowed:
            item["allowed"] = allowed
        out.append(item)
    return out


# the error type of a query parameter's bool that is not true or false
# (service.schemas.common.QueryBool)
QUERY_BOOL_ERROR = "query_bool"
BODY_ALLOWED = "a UTF-8 JSON document of the documented shape"
# pydantic's error types of a value that is not the object asked for; with "missing",
# those of an object (or the JSON document) asked for and not there
OBJECT_TYPES = ("model_type", "model_attributes_type", "dict_type")
OBJECT_EXPECTED = (*OBJECT_TYPES, "missing")


def _allowed_by_kind(err: dict[str, Any], request: Request | None,
                     loc: list[str | int]) -> str | None:
    """The allowed values of a field without a range: a field of fixed words (its words),
    an object (its fields, read off the published schema), the body itself (a JSON
    document); None where none of these applies."""
    if err.get("type") in ("literal_error", "enum"):
        return str((err.get("ctx") or {}).get("expected", "")) or None
    if err.get("type") not in OBJECT_EXPECTED:
        return None
    fields = _sibling_fields(request, [*loc, ""]) if request is not None else []
    if fields:
        return "a JSON object of " + ", ".join(fields) + " (the schema at /docs)"
    return BODY_ALLOWED if loc == ["body"] else None


def short_name(part: str | int, limit: int = 80) -> str | int:
    """A location's name cut to ``limit`` characters with its length said: a field no
    schema has, of 50,000 characters, was echoed whole in loc, field and detail (a 150 kB
    problem); every field the service takes is far shorter."""
    if not isinstance(part, str) or len(part) <= limit:
        return part
    return f"{part[:limit - 20]}... ({len(part)} characters)"


def short_input(value: Any, limit: int = 40) -> str:
    """``repr(value)`` cut to ``limit`` characters: a message never echoes a long input."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _unparsed_body(message: str) -> dict[str, Any]:
    """The error entry of a body that is not the JSON document asked for."""
    return {"loc": ["body"], "field": "body", "message": message,
            "allowed": BODY_ALLOWED}


def _not_json_body(request: Request, errors: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """A body sent as another media type (curl -d sends a form; a text/plain fetch) is
    not read as JSON, and pydantic says only "Input should be a valid dictionary": the
    error names the Content-Type that was sent instead."""
    media_type = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if media_type == "application/json" or media_type.endswith("+json"):
        return errors
    sent = f"Content-Type {short_input(media_type, 60)}" if media_type else "no Content-Type"
    return [{**e, "message": f"the body is not read as JSON: it came with {sent}",
             "allowed": "Content-Type: application/json"}
            if e.get("loc") == ["body"] else e for e in errors]


def _allowed_methods(request: Request) -> list[str]:
    """The methods the published contract has for the request's path; for a path outside
    it (the explorer's page, /docs, /openapi.json, static files: their Allow was empty)
    the methods of the routes that match it."""
    from starlette.routing import Match

    path = request.url.path
    methods: set[str] = set()
    for template, operations in request.app.openapi()["paths"].items():
        pattern = re.sub(r"\\\{[^/]+?\\\}", "[^/]+", re.escape(template))
        if re.fullmatch(pattern, path):
            methods |= {m.upper() for m in operations}
    if not methods:     # the full path: inside a mount the scope's path is the mount's rest
        scope = {**request.scope, "path": path, "root_path": ""}
        for route in request.app.routes:
            if route.matches(scope)[0] != Match.NONE:
                methods |= set(getattr(route, "methods", None) or ("GET", "HEAD"))
    return sorted(methods)


def install_error_handlers(app: FastAPI) -> None:
    """Route every error through ``problem_for`` (validation errors get one entry per field)."""

    async def on_validation(request: Request, exc: RequestValidationError) -> JSONResponse:
        every = _one_branch(list(exc.errors()))
        errors = _not_json_body(request, _validation_errors(every[:MAX_LISTED_ERRORS],
                                                            request))
        detail = "; ".join(
            f"{e['field'] or e['loc'][0]}: {e['message']}"
            + (f" (allowed: {e['allowed']})" if "allowed" in e else "") for e in errors)
        if len(every) > len(errors):
            detail += (f"; and {len(every) - len(errors)} more errors (the first "
                       f"{len(errors)} of {len(every)} are listed)")
        return Problem(422, "Invalid input", detail, "invalid-input",
                       errors=errors).response(request)

    async def on_http(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        if exc.status_code == 400 and exc.detail == BODY_NOT_PARSED:
            # FastAPI's 400 for a body json.loads cannot take (nested deeper than the
            # parser's recursion limit, not UTF-8, an integer of > 4300 digits): an input
            # error like any other JSON one; the integer named where it sits
            from service.unheld_numbers import unheld_number_error  # imports this module

            unheld = unheld_number_error(await request.body())
            if unheld is not None:
                return problem_for(unheld).response(request)
            return Problem(422, "Invalid input", "body: cannot be parsed as JSON",
                           "invalid-input", errors=[_unparsed_body("cannot be parsed as JSON")]
                           ).response(request)
        if exc.status_code == 413:  # the body limit, met while a chunked body streamed in
            return problem_for(PayloadTooLargeError(str(exc.detail))).response(request)
        titles = {404: "Not found", 405: "Method not allowed", 406: "Not acceptable"}
        headers = dict(exc.headers or {})
        if exc.status_code == 405:  # every method of the path (Starlette names one route's)
            headers["Allow"] = ", ".join(_allowed_methods(request))
        problem = Problem(exc.status_code, titles.get(exc.status_code, "HTTP error"),
                          str(exc.detail), f"http-{exc.status_code}", headers=headers)
        return problem.response(request)

    async def on_domain(request: Request, exc: Exception) -> JSONResponse:
        return problem_for(exc).response(request)

    async def on_unexpected(request: Request, exc: Exception) -> JSONResponse:
        log.exception("unexpected error on %s %s", request.method, request.url.path)
        return problem_for(exc).response(request)

    app.add_exception_handler(RequestValidationError, on_validation)  # type: ignore[arg-type]
    app.add_exception_handler(StarletteHTTPException, on_http)  # type: ignore[arg-type]
    app.add_exception_handler(BalloonError, on_domain)
    app.add_exception_handler(Exception, on_unexpected)
