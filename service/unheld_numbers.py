"""A JSON body's number that a 64-bit float does not hold is refused as written.

Python's ``json`` reads ``1e-400`` as 0.0 and ``1e400`` (or a 400-digit integer) as inf
before any schema sees it, and a 5000-digit integer not at all: ``"L_mm": 1e400`` was told
"Input should be a finite number", a 5000-digit one "cannot be parsed as JSON", an inline
material's ``"mu_kpa": [1e-400]`` "every Ogden term has mu = 0", a target's ``"angle_deg":
1e-400`` "got 0.0", and ``"pressures_pa": [1e-400]`` was answered at 0 Pa -- each a
different number from the one the client wrote. No JSON writer of doubles writes such a
number; it is a hand-written or a unit-conversion bug, and the answer names it as written
with the field's range (``solver.number_text.unheld_words``), on every route alike.

One app-level dependency, beside ``service.repeated_fields``: it runs before the body is
validated; an integer of more than 4300 digits, which FastAPI's own parse cannot take, is
named by the error handler the same way (``service.errors``). The body is parsed again
(``surrogate.json_repeats``, whose numbers keep their text where a float does not hold
it) only when its text holds a number that may be one: a 3-digit exponent or a run of
309 digits.
"""

from __future__ import annotations

import re

from fastapi import Request

from service.errors import FieldError, field_range, short_name
from solver.number_text import unheld, unheld_words
from surrogate.json_repeats import loads_with_repeats

#: the text of a number a float may not hold: 1e-400, 1E+400, 400 digits in a row
MAYBE_UNHELD = re.compile(rb"[eE][+-]?[0-9]{3}|[0-9]{309}")


def unheld_number_error(body: bytes) -> FieldError | None:
    """The 422 of the first number of a JSON body whose text a float does not hold, given
    where a number goes; None when there is none (or the body is not JSON)."""
    if not MAYBE_UNHELD.search(body):
        return None
    try:
        document, _ = loads_with_repeats(body)
    except (ValueError, RecursionError):
        return None     # not JSON: FastAPI's own parse refuses it
    for path, number in unheld(document):
        # a number field (each has a range); elsewhere -- an object, a choice of words,
        # an unknown field -- the schema refuses a number whatever its value
        loc = ("body", *(short_name(p) for p in path))
        allowed = field_range(loc)
        if allowed is not None:
            return FieldError(loc, unheld_words(number), allowed=allowed)
    return None


async def refuse_unheld_numbers(request: Request) -> None:
    """Refuse (422 at its location, with the field's range) the first number of a JSON
    body whose text a float does not hold, given where a number goes."""
    if request.method in ("POST", "PUT", "PATCH"):
        error = unheld_number_error(await request.body())
        if error is not None:
            raise error
