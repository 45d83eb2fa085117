"""A number written as text -- a command-line option's word, a query parameter, a cell of
measured data -- is read by one rule: ASCII decimal digits, as JSON writes numbers
(``1000``, ``-2.5``, ``.5``, ``1e3``), with an optional ``+`` and the white space around
it; the words ``nan`` and ``inf`` (``infinity``) are read as such, for the range checks
after them to refuse by name.

Python's ``float`` and ``int`` and pydantic's lax mode read more: ``1_000`` (``7_1`` was
L = 71 mm) and the digits of any script (``١٠٠٠``, ``１０００``), which a JSON number never
carries, so the same value was refused in a JSON body and taken on the command line, in
a query or in a data file. (The service's query models: ``service.schemas.common``.)
"""

from __future__ import annotations

import math
import re
import sys
from collections.abc import Iterator
from typing import Any

_UNSIGNED = r"(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
_DECIMAL = rf"[+-]?{_UNSIGNED}"
_FLOAT = re.compile(rf"(?:{_DECIMAL}|[+-]?(?:nan|inf|infinity))", re.IGNORECASE)
_INT = re.compile(r"[+-]?[0-9]+")
#: a command-line word that is a negative number, not an option: argparse's own matcher
#: takes -5 and -2.5 only, so ``--angles-deg -1.5e1`` said "expected at least one argument"
#: and ``--L-mm -1e3`` "expected one argument", never the option's range
NEGATIVE_NUMBER = re.compile(rf"^-(?:{_UNSIGNED}|nan|inf|infinity)$", re.IGNORECASE)

#: the allowed forms, in words (every refusal states them)
NUMBER_FORM = "ASCII decimal digits, as 1000, 2.5 or 1e-3"
INTEGER_FORM = "ASCII decimal digits, as 5"


def is_number_text(text: str) -> bool:
    """Whether ``text`` is a number written in NUMBER_FORM (or nan, inf)."""
    return bool(_FLOAT.fullmatch(text.strip()))


def is_integer_text(text: str) -> bool:
    """Whether ``text`` is a whole number written in INTEGER_FORM."""
    return bool(_INT.fullmatch(text.strip()))


class WrittenNumber(float):
    """A number whose text a float does not hold (``1e-400`` underflows to 0.0, ``1e400``
    overflows to inf): the float's value, shown as written. A range check's "got {value!r}"
    or "got {value:g}" then says "got 1e-400", not "got 0.0", a different number."""

    text: str

    def __new__(cls, value: float, text: str) -> WrittenNumber:
        number = super().__new__(cls, value)
        number.text = text
        return number

    def __repr__(self) -> str:
        return self.text

    __str__ = __repr__

    def __format__(self, spec: str) -> str:
        return self.text if not spec or spec[-1] in "gGr" else super().__format__(spec)

    def __reduce__(self) -> tuple:
        return (WrittenNumber, (float(self), self.text))


def ascii_float(text: str) -> float:
    """``text`` as a float, if it is written in NUMBER_FORM; ValueError otherwise (its
    message says the form). A value the float does not hold is a WrittenNumber."""
    if not is_number_text(text):
        raise ValueError(f"{text!r} is not a number ({NUMBER_FORM})")
    return written_float(text)


def written_float(text: str) -> float:
    """``float(text)`` of a number's text (NUMBER_FORM, or a JSON number's), a
    WrittenNumber where the float does not hold it: non-zero digits that underflow to 0,
    a finite number that overflows to inf. ``json.loads(parse_float=...)``."""
    value = float(text)
    written = text.strip()
    digits = re.split("[eE]", written)[0]
    if ((value == 0 and re.search("[1-9]", digits))
            or (math.isinf(value) and "inf" not in written.lower())):
        return WrittenNumber(value, written)
    return value


def written_int(text: str) -> int | float:
    """``int(text)`` of a JSON integer's text; one larger than a float holds (above
    about 1.8e308: 309 digits and more) is a WrittenNumber of inf, its digits not
    converted past 4300 (Python's own limit: json.loads raised "Exceeds the limit").
    ``json.loads(parse_int=...)``."""
    digits = text.lstrip("+-")
    if len(digits) < 309:
        return int(text)
    if len(digits) <= 4300 and abs(value := int(text)) <= sys.float_info.max:
        return value
    return WrittenNumber(-math.inf if text.startswith("-") else math.inf, text)


#: json.loads' hooks that keep a number's text where the float does not hold it
JSON_NUMBER_HOOKS = {"parse_float": written_float, "parse_int": written_int}

#: what a 64-bit float holds, in words
HELD_RANGE = "sizes about 5e-324 to 1.8e308, or 0"


def unheld_words(number: WrittenNumber) -> str:
    """Why a WrittenNumber is refused where it is given as a value: its text (cut) and
    the number the float would read it as -- a different number from the one written."""
    text = number.text if len(number.text) <= 40 else (
        f"{number.text[:20]}... ({len(number.text)} characters)")
    read = "0" if number == 0 else f"{float(number)}"
    return f"{text} does not fit a 64-bit float ({HELD_RANGE}): it would be read as {read}"


def ascii_int(text: str) -> int:
    """``text`` as an int, if it is written in INTEGER_FORM; ValueError otherwise."""
    if not is_integer_text(text):
        raise ValueError(f"{text!r} is not a whole number ({INTEGER_FORM})")
    return int(text)


def nodes(document: Any) -> Iterator[tuple[tuple[str | int, ...], Any]]:
    """Every value of a parsed document (JSON, TOML) with its path (keys and list
    indices), depth first, the document itself first (a stack, not recursion: a document
    nested as deep as its parser takes is walked too)."""
    stack: list[tuple[tuple[str | int, ...], Any]] = [((), document)]
    while stack:
        path, value = stack.pop()
        yield path, value
        items = value.items() if isinstance(value, dict) else (
            enumerate(value) if isinstance(value, list) else ())
        stack.extend(reversed([(path + (key,), item) for key, item in items]))


def unheld(document: Any) -> Iterator[tuple[tuple[str | int, ...], WrittenNumber]]:
    """(path, number) of each number of a parsed document whose text a float does not
    hold (read with JSON_NUMBER_HOOKS, or ``tomllib.loads(parse_float=written_float)``),
    depth first. An integer beyond a float's range that the parser kept as an int (TOML:
    tomllib has no hook for integers; ``mu_kpa = [1<4000 digits>]`` was an OverflowError
    where it was used) is one too, a WrittenNumber of infinity."""
    for path, value in nodes(document):
        if isinstance(value, WrittenNumber):
            yield path, value
        elif type(value) is int and abs(value) > sys.float_info.max:
            yield path, WrittenNumber(math.inf if value > 0 else -math.inf, _int_text(value))


def _int_text(number: int) -> str:
    """An integer's text: decimal, or hexadecimal past the digits Python converts to
    decimal (``0xfff...`` of 5000 digits; its repr raised ValueError)."""
    try:
        return str(number)
    except ValueError:
        return f"{number:#x}"
