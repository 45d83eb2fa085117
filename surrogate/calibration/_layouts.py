"""Lab layouts the loader does not read, refused with how to convert them.

A lab's spreadsheet or logger may put the units in a row under the header (``Time`` over
``s``), write the time as a clock (``01:04.5``, a header ``Time (mm:ss)``), or give each
specimen its own columns (``Pressure S1 (kPa)``, ``Angle S1 (deg)``, one row per time).
A logger may also write lines of text above the header (its name, the operator, the
batch) that are no '#' comments. Each was refused with an error that did not say what
the file held (``Time: read as time_s, but no unit is given for time``, ``'mm:ss' is not
a unit of time``, ``curve_id: required column is missing``: benchmarks/lab_rig_sets.py
N23, N26, N27, N30); the error now names the layout and the conversion, on one line.
"""

from __future__ import annotations

import itertools
import re

from solver.number_text import is_number_text
from surrogate.calibration._errors import DataError
from surrogate.calibration._headers import read_header, split_header, unit_of

#: a time of day or a stopwatch's reading: 01:04, 01:04.5, 0:01:04.5, and their formats
CLOCK = re.compile(r"\s*(\d+:)?\d+:\d+([.,]\d*)?\s*|\s*(h+:)?m+:s+([.,]s*)?\s*", re.I)


def is_clock(text: object) -> bool:
    """Whether ``text`` is a clock reading or format (mm:ss, hh:mm:ss.s), not seconds."""
    return isinstance(text, str) and CLOCK.fullmatch(text) is not None


CLOCK_HOW = "the time in seconds from the pump's start, 'Time (s)' (01:04.5 is 64.5)"


def layout_error(exc: DataError, first_row: dict | None) -> DataError:
    """``exc`` (a header ``read_headers`` refused) said as the layout it comes from: a
    clock for a unit (``Time (mm:ss)``), or a header without a unit over a row that holds
    units (``Time`` over ``s``); else ``exc`` itself."""
    _, unit = split_header(exc.column)
    if "not a unit of time" in str(exc) and is_clock(unit):
        return DataError(exc.column, f"read as time_s, but {unit!r} is a clock, not a unit "
                         "of time", None, CLOCK_HOW)
    cell = (first_row or {}).get(exc.column)
    if "no unit is given" not in str(exc) or not isinstance(cell, str) or not unit_of(cell):
        return exc
    units = ", ".join(f"{k} ({v})" for k, v in first_row.items()
                      if isinstance(v, str) and v.strip() and unit_of(v))
    return DataError(exc.column, f"the row under the header holds units ({units}): a units "
                     "row is not read", None, f"each unit in its header, '{exc.column} "
                     f"({cell.strip()})', and the units row deleted")


def one_column_per_specimen(columns: set, numeric: tuple[str, ...]) -> DataError | None:
    """The error for a wide layout: two or more headers that read as a quantity once a
    last word (the specimen's label) is taken off its name (``Pressure S1 (kPa)``)."""
    wide = []
    for header in sorted(map(str, columns)):
        name, unit = split_header(header)
        words = name.split()
        if len(words) < 2:
            continue
        plain = " ".join(words[:-1]) + (f" ({unit})" if unit else "")
        try:
            if read_header(plain, numeric) is not None:
                wide.append(header)
        except DataError:
            continue
    if len(wide) < 2:
        return None
    shown = ", ".join(repr(h) for h in wide[:3]) + (", ..." if len(wide) > 3 else "")
    return DataError("curve_id", f"required column is missing: the file has one column per "
                     f"specimen ({shown}), which is not read", None,
                     "one row per reading, a curve_id column naming its specimen and one "
                     "column per quantity ('Pressure (kPa)', 'Angle (deg)')")


#: how many lines below the first a header standing under a logger's text is looked for
PREAMBLE_LINES = 20
#: how much of each such line is read for column names: a header's worth, not a stray
#: line of 10^5 separators (each name costs a header reading)
PREAMBLE_PARTS = 1000
PREAMBLE_CHARS = 65536
PREAMBLE_HOW = "each line above the header starting with '#' (a comment), or deleted"
FOOTER_HOW = "each line of text below the readings starting with '#' (a comment), or deleted"


def header_below_text(lines: list[list[object]], required: tuple[str, ...],
                      numeric: tuple[str, ...]) -> int | None:
    """The index in ``lines`` (each a line's cells, as a CSV row or a JSON row's values)
    of the first line among the first ``PREAMBLE_LINES`` that names every required
    column (by name, or as a header with a unit: ``Pressure (kPa)``), or None. A cell may
    hold a whole line (a ';'-separated header read as one cell of a ','-separated
    first line), so each is split on ',', ';' and tabs."""
    for k, cells in enumerate(lines[:PREAMBLE_LINES]):
        named = set()
        parts = (part for cell in cells if isinstance(cell, str)
                 for part in re.split(r"[,;\t]", cell[:PREAMBLE_CHARS]))
        for part in itertools.islice(parts, PREAMBLE_PARTS):
            try:
                reading = read_header(part.strip(), numeric)
            except DataError:
                continue
            named.add(reading.column if reading is not None else part.strip())
        if set(required) <= named:
            return k
    return None


def text_below_readings(row: dict, line: int) -> DataError | None:
    """The error for a line of text after the last reading (a logger's "Measurement
    stopped by user at ..."): a row whose first cell is text and whose others are empty,
    named with its line, as the text above a header is (until 2026-12-08 it was read as a
    reading and refused as "run: row 52: missing run", benchmarks/lab_rig_sets.py N60);
    None for any other row."""
    cells = list(row.values())
    first = cells[0] if cells else None
    if (not isinstance(first, str) or not first or is_number_text(first)
            or any(c not in (None, "") for c in cells[1:])):
        return None
    shown = repr(first if len(first) <= 60 else first[:57] + "...")
    return DataError("row", f"line {line} holds text after the last reading ({shown}), "
                     "which is not a reading", None, FOOTER_HOW)


def text_above_header(above: list[str], line: int | None = None) -> DataError:
    """The error for a file whose header stands below lines of text (a logger's name,
    the operator): the text is named, and where the header is when the line is known."""
    first = str(above[0]).strip()
    shown = repr(first if len(first) <= 60 else first[:57] + "...") + (
        ", ..." if len(above) > 1 else "")
    where = f"line {line} holds the header" if line is not None else "the header stands"
    return DataError("header", f"{where} below text ({shown}), which is not read: a file's "
                     "first line that is no comment is its header", None, PREAMBLE_HOW)
