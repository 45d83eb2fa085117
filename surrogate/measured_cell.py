"""One value of a measured row as JSON gives it (a data file's row object, or a row of
``POST /v1/calibrate``): a finite number, text or null, and nothing else -- ``true``
would be read as 1 (or as the text "True" in a curve's id), a list or an object as no
number, a 400-digit integer overflows a float, and a number whose text a float does not
hold (``1e-400``, read as 0) is another number than the one written, as a JSON number or
as text. A file and a request are held to this one rule; each column's range is checked
afterwards (``surrogate.calibration``, docs/measured-data.md).
"""

from __future__ import annotations

import math

from solver.number_text import WrittenNumber, is_number_text, unheld_words, written_float

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
        if len(value) > MAX_CELL_CHARACTERS:
            return f"text of {len(value)} characters (at most {MAX_CELL_CHARACTERS})"
        number = written_float(value) if is_number_text(value) else None  # a CSV cell
        return unheld_words(number) if isinstance(number, WrittenNumber) else None
    if isinstance(value, WrittenNumber):
        return unheld_words(value)
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
