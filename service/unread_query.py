"""A query string on an operation that reads none is refused, not ignored.

``POST /v1/predict?model=paper`` was answered by the emulator, the body's default, as if
the query string were not there; ``GET /v1/health?verbose=1`` likewise. An operation
with query parameters refuses one it does not take (its schema forbids extra fields,
with a "did you mean"); an operation without any (every POST, the health, materials and
effects lists, one record, one job) refuses any, naming it: its inputs are the body or
the path. Pages outside the contract (the explorer keeps its view in its own address)
are not checked.

One app-level dependency, beside ``service.repeated_fields``.
"""

from __future__ import annotations

from fastapi import Request

from service.errors import FieldError
from service.repeated_fields import query_parameters


async def refuse_unread_query(request: Request) -> None:
    """Refuse (422 at ``("query", name)``) the first query parameter of a request whose
    operation takes none."""
    if not request.query_params:
        return
    taken = query_parameters(request)
    if taken is None or taken[0]:
        return
    name = next(iter(request.query_params))[:64]      # a 20,000-character name: cut
    where = "the JSON body" if request.method in ("POST", "PUT", "PATCH") else "the path"
    raise FieldError(("query", name), f"{request.method} {request.scope['route'].path} "
                     f"takes no query parameters: {name!r} would be ignored",
                     allowed=f"no query string; this operation's input is {where} "
                     "(the schema at /docs)")
