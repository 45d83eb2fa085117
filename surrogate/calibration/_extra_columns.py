"""A logger's or a spreadsheet's columns that carry nothing the calibration reads -- the
rig's temperature, an operator's note, the humidity -- taken out and said, not a reason
to refuse the file (benchmarks/lab_rig_sets.py N47, N53: `Temperature (C)` and `Note`
were refused as unknown columns until 2026-12-07).

Only a header that cannot be a column the loader reads, misspelt or in another form, is
taken out: plain printable text (no control, format or hidden characters) of at most
``MAX_CHARS`` characters; no unit of a quantity the calibration reads (``UNITS``: a
``Druk (kPa)`` is a pressure the loader failed to name, not a note); none of its words a
name the loader reads a column by, or within a typing slip of one (difflib's ratio at
least ``NEAR``: ``angel_deg``, ``Presure``, ``flow rate``); not a single letter (``T`` is
a temperature or the body's thickness). Every other unknown header stays refused, naming
it: a typo must not silently drop a reading.
"""

from __future__ import annotations

import difflib
import re

from surrogate.calibration._headers import QUANTITY_NAMES, split_header, unit_of

#: a longer header is no logger's extra column
MAX_CHARS = 40
#: difflib's ratio from which a word is a slip of a name the loader reads
NEAR = 0.75
#: words the loader names columns by besides the canonical names' own parts
NAMED = ("sample", "specimen", "id", "date", "timestamp", "epoch", "clock", "stamp",
         "pressure", "angle", "bend", "flow", "rate", "volume", "force", "time", "curve",
         "run", "pump", "body", "membrane", "material", "thickness", "length", "width",
         "height", "chamber", "design")


def _words(text: str) -> list[str]:
    return [w for w in re.split(r"[^0-9a-zäöüßθ]+", text.lower()) if w]


def _vocabulary(known: set[str]) -> set[str]:
    out = set(NAMED)
    for name in known | {n for names in QUANTITY_NAMES.values() for n in names}:
        out.update(w for w in _words(name) if len(w) > 1)
    return out


def not_a_reading(header: object, known: set[str]) -> bool:
    """Whether ``header`` is a column of nothing the calibration reads (the module's
    docstring), given the canonical columns ``known``."""
    if not isinstance(header, str) or not header.strip() or len(header) > MAX_CHARS:
        return False
    if not header.isprintable():
        return False
    name, unit = split_header(header.strip())
    if unit is not None and unit_of(unit) is not None:
        return False
    words = _words(name)
    if not words or any(len(w) == 1 for w in words):
        return False
    vocabulary = _vocabulary(known)
    joined = "_".join(words)
    if difflib.get_close_matches(joined, [k.lower() for k in known], n=1, cutoff=NEAR):
        return False
    return not any(w in vocabulary or difflib.get_close_matches(w, vocabulary, n=1,
                                                                cutoff=NEAR)
                   for w in words if len(w) > 1)


def extra_columns_read(rows: list, known: set[str]) -> tuple[list, tuple[dict, ...]]:
    """``rows`` without the columns of nothing the calibration reads, and per such column
    {'header', 'read_as': None, 'reading': a sentence}. Rows that are not all objects
    are returned as they are (the caller refuses them)."""
    if not all(isinstance(r, dict) for r in rows):
        return rows, ()
    headers = [h for h in dict.fromkeys(k for r in rows for k in r)
               if h not in known and not_a_reading(h, known)]
    if not headers:
        return rows, ()
    drop = set(headers)
    rows = [{k: v for k, v in r.items() if k not in drop} for r in rows]
    return rows, tuple({"header": h, "read_as": None,
                        "reading": f"`{h}` not read: no quantity the calibration uses"}
                       for h in headers)
