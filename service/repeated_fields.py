"""A request field given twice is refused, not read as its last value.

JSON leaves an object's repeated name to the parser (RFC 8259, section 4: "the names
within an object SHOULD be unique"); Python's ``json`` keeps the last one, and FastAPI
reads a single-valued query parameter given twice as its last value too. A body with
``"L_mm": 5`` and ``"L_mm": 50`` says two things, and answering one of them silently is a
guess: the request is refused with a 422 problem naming the field and where it sits.
Query parameters that are lists (``measured_pressure_pa`` of /v1/predict/plot) are
repeated by design and pass.

One app-level dependency, run after FastAPI has read and parsed the body (a body that is
not JSON is refused by FastAPI's own parse first) and before any route's work.
"""

from __future__ import annotations

from fastapi import Request

from service.errors import FieldError, short_name
from surrogate.json_repeats import loads_with_repeats

BODY_ALLOWED = "each field once per JSON object"
QUERY_ALLOWED = "each parameter once; only a list parameter repeats (one value each time)"


def repeated_body_field(body: bytes) -> tuple[str | int, ...] | None:
    """``("body", ..., name)`` of the first name repeated within one object of a JSON
    body, or None (also for a body that is not JSON: its parse error is FastAPI's)."""
    try:
        _, loc = loads_with_repeats(body)
    except (ValueError, RecursionError):
        return None
    return None if loc is None else ("body", *loc)


def query_parameters(request: Request) -> tuple[set[str], set[str]] | None:
    """(every query parameter, those taking a list) of the request's route, read off its
    published schema; None for a route outside the contract (the pages)."""
    try:
        op = request.app.openapi()["paths"][request.scope["route"].path][request.method.lower()]
    except (KeyError, AttributeError):
        return None
    names, lists = set(), set()
    for param in op.get("parameters", ()):
        if param.get("in") != "query":
            continue
        names.add(param["name"])
        schema = param.get("schema", {})
        if any(s.get("type") == "array" for s in (schema, *schema.get("anyOf", ()))):
            lists.add(param["name"])
    return names, lists


async def refuse_repeated_fields(request: Request) -> None:
    """Refuse (422, the field's location) a single-valued query parameter given more than
    once, or a name repeated within one object of a JSON body."""
    keys = [k for k, _ in request.query_params.multi_items()]
    if len(keys) != len(set(keys)):
        names, lists = query_parameters(request) or (set(), set())
        for key in dict.fromkeys(keys):
            if key in names and key not in lists and keys.count(key) > 1:
                raise FieldError(("query", key), f"is given {keys.count(key)} times in the "
                                 "query string; which one is meant is not guessed",
                                 allowed=QUERY_ALLOWED)
    if request.method in ("POST", "PUT", "PATCH"):
        body = await request.body()
        if body:
            loc = repeated_body_field(body)
            if loc is not None:      # a name no schema has, of 30,000 characters: cut
                loc = tuple(short_name(p) for p in loc)
                where = ".".join(str(p) for p in loc[1:-1])
                raise FieldError(loc, f"is given more than once in "
                                 f"{'the object ' + where if where else 'the body'}; which "
                                 "value is meant is not guessed", allowed=BODY_ALLOWED)
