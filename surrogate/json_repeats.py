"""Names repeated within one JSON object, found instead of read as their last value.

JSON leaves an object's repeated name to the parser (RFC 8259, section 4: "the names
within an object SHOULD be unique"), and Python's ``json`` keeps the last one: a lab's
row ``{"angle_deg": 5, "angle_deg": 50}`` would be read as 50 deg. ``loads_with_repeats``
parses a document and says where the first repeat sits, so the caller can refuse it
naming the place (the HTTP body, a calibration file). Its numbers are read by
``solver.number_text.JSON_NUMBER_HOOKS``: one whose text a float does not hold
(``1e-400``, ``1e400``) is a ``WrittenNumber``, for the caller to refuse as written
(``solver.number_text.unheld``).
"""

from __future__ import annotations

import json
from typing import Any

from solver.number_text import JSON_NUMBER_HOOKS, nodes

Path = tuple[str | int, ...]


class _Object(dict):
    """A parsed JSON object that remembers the names it was given more than once."""

    repeated: tuple[str, ...] = ()


def _first_repeat(document: Any) -> Path | None:
    """The location of the first repeated name in a parsed document, depth first."""
    return next((path + (value.repeated[0],) for path, value in nodes(document)
                 if isinstance(value, _Object) and value.repeated), None)


def loads_with_repeats(text: str | bytes) -> tuple[Any, Path | None]:
    """``(document, location)``: the parsed document (plain dicts and lists) and the path
    of its first name repeated within one object (keys and list indices, ending with the
    name), or None. Raises what ``json.loads`` raises for a text that is not JSON."""
    found = False

    def hook(pairs: list[tuple[str, Any]]) -> dict:
        nonlocal found
        obj = _Object(pairs)
        if len(obj) != len(pairs):
            seen: set[str] = set()
            obj.repeated = tuple(dict.fromkeys(
                k for k, _ in pairs if k in seen or seen.add(k)))  # type: ignore[func-returns-value]
            found = True
        return obj

    document = json.loads(text, object_pairs_hook=hook, **JSON_NUMBER_HOOKS)
    return document, (_first_repeat(document) if found else None)
