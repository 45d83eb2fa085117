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

import re

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


def ascii_float(text: str) -> float:
    """``text`` as a float, if it is written in NUMBER_FORM; ValueError otherwise (its
    message says the form)."""
    if not is_number_text(text):
        raise ValueError(f"{text!r} is not a number ({NUMBER_FORM})")
    return float(text)


def ascii_int(text: str) -> int:
    """``text`` as an int, if it is written in INTEGER_FORM; ValueError otherwise."""
    if not is_integer_text(text):
        raise ValueError(f"{text!r} is not a whole number ({INTEGER_FORM})")
    return int(text)
