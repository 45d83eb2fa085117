"""One value of a measured row as JSON gives it (a data file's row object, or a row of
``POST /v1/calibrate``): a finite number, text or null, and nothing else -- ``true``
would be read as 1 (or as the text "True" in a curve's id), a list or an object as no
number, a 400-digit integer overflows a float. A file and a request are held to this one
rule; each column's range is checked afterwards (``surrogate.calibration``,
docs/measured-data.md).
"""

from __future__ import annotations

import math

MAX_CELL_INT = 10**15  # larger integers are no measurement (and overflow a float)
MAX_CELL_CHARACTERS = 200
#: what a cell may hold, as an error's "allowed" words
CELL_WORDS = (f"a finite number (|value| <= 1e15), text (at most {MAX_CELL_CHARACTERS} "
              "characters) or null; each column's range: docs/measured-data.md")


def cell_problem(value: object) -> str | None:
    """Why ``value`` is no measured cell, in words; None when it is one."""
    if value is None:
        return None
    if isinstance(value, str):
        return (f"text of {len(value)} characters (at most {MAX_CELL_CHARACTERS})"
                if len(value) > MAX_CELL_CHARACTERS else None)
    if isinstance(value, bool) or not isinstance(value, int | float):
        what = (str(value).lower() if isinstance(value, bool) else "a list"
                if isinstance(value, list) else "an object" if isinstance(value, dict)
                else type(value).__name__)      # as JSON names them
        return f"{what} is not a measured value: give a number, text or null"
    if isinstance(value, int) and abs(value) > MAX_CELL_INT:
        return (f"an integer of {len(str(abs(value)))} digits is out of range "
                f"(|value| <= 1e15)")
    if not math.isfinite(value):
        return "NaN and infinity are not measured values"
    return None
