"""Numeric command-line options whose text is not a number: argparse's own message
("argument --L-mm: invalid float value: 'abc'") names the option but no range, so a
design option carries its allowed range (``number_action``), and the parser's error states
it too:

    balloon predict: error: argument --L-mm: 'abc' is not a number (ASCII decimal
    digits, as 1000, 2.5 or 1e-3; allowed: 0.5 to 60 mm)

``--help`` states the same range beside each option (``help_with_allowed``, added by
``service.cli.Parser``'s formatter): a help text never repeats a range by hand (``balloon
solve --help`` had said ``--flow-ul-s`` took up to 1e6 ul/s, its check 1000).

The ranges come from the tables that check the values afterwards
(``solver.design.LIMITS_MM``, ``solver.design_space.BOX_MM``, the stiffness scales'):
this module only parses, the range checks stay where they are. Every number option
carries one (a test checks): a word the parser refuses -- ``abc``, or ``1e-400``, which a
float reads as 0 -- is told the option's range whatever the check after it would say.

An integer option (``--workers``, ``--port``, ...) is the same: ``int_action`` attaches
its range for the parser's refusal of ``two`` or ``1.5``, and ``checked_int`` refuses a
whole number outside it afterwards, both from one (lo, hi) of the command's and in one
phrasing, ``1 <= N <= 256``.
"""

from __future__ import annotations

import argparse

from solver.design import LIMITS_MM
from solver.design_space import STIFFNESS_SCALE_LIMITS
from solver.errors import InputError
from solver.settings import SETTING_RANGES

#: a setting's unit, by the end of its name
_UNITS = {"_deg": "deg", "_pa": "Pa", "_ul_s": "ul/s", "_n_per_m": "N/m"}


def range_text(lo: float, hi: float, unit: str = "") -> str:
    """``"0.5 to 60 mm"``: an option's allowed range in words."""
    return f"{lo:g} to {hi:g} {unit}".rstrip()


def number_action(action: argparse.Action, lo: float, hi: float,
                  unit: str = "") -> argparse.Action:
    """``action`` (a float option) with its allowed range ``lo``..``hi`` attached: text
    that is not a number is then told the range too (``service.cli.Parser.error``)."""
    return allowed_action(action, range_text(lo, hi, unit))


def allowed_action(action: argparse.Action, allowed: str) -> argparse.Action:
    """``action`` with its allowed values in words (``"0 to 20000 Pa"``) attached, for
    the parser's refusals (``service.cli.Parser.error``)."""
    action.allowed = allowed  # type: ignore[attr-defined]
    return action


def help_with_allowed(action: argparse.Action, text: str | None) -> str | None:
    """``text``, an option's help, with the allowed values attached to ``action`` said
    too, unless it says them already: ``"chamber length, mm (default 7.1)"`` becomes
    ``"chamber length, mm (default 7.1; allowed: 0.5 to 60 mm)"``."""
    allowed = getattr(action, "allowed", None)
    if not allowed or text == argparse.SUPPRESS or (text and allowed in text):
        return text
    said = allowed.replace("%", "%%")     # argparse formats the help with %(default)s
    if not text:
        return f"allowed: {said}"
    if text.endswith(")"):
        return f"{text[:-1]}; allowed: {said})"
    return f"{text} (allowed: {said})"


def int_words(name: str, lo: int, hi: int, unit: str = "") -> str:
    """``"1 <= N <= 256"``: an integer option's allowed range in words, the parser's
    and the range check's alike."""
    return f"{lo} <= {name} <= {hi} {unit}".rstrip()


def int_action(action: argparse.Action, name: str, lo: int, hi: int,
               unit: str = "") -> argparse.Action:
    """``action`` (an int option) with its allowed range ``lo``..``hi`` attached, in the
    words of ``checked_int`` (``name`` is its metavar as the help shows it)."""
    return allowed_action(action, int_words(name, lo, hi, unit))


def checked_int(flag: str, value: int, name: str, lo: int, hi: int, unit: str = "") -> int:
    """``value`` of the int option ``flag``; InputError naming it and its range (the
    words ``int_action`` attached) unless ``lo <= value <= hi``."""
    if not lo <= value <= hi:
        raise InputError(flag, f"got {value}", int_words(name, lo, hi, unit))
    return value


def attach_setting_ranges(parser: argparse.ArgumentParser) -> None:
    """Attach its allowed range (``solver.settings.SETTING_RANGES``, by the option's
    dest) to each solver-setting option of ``parser``."""
    for action in parser._actions:  # noqa: SLF001 - argparse keeps its options there
        if action.dest in SETTING_RANGES and action.type is float:
            unit = next((u for end, u in _UNITS.items() if action.dest.endswith(end)), "")
            number_action(action, *SETTING_RANGES[action.dest], unit)


def attach_design_ranges(parser: argparse.ArgumentParser) -> None:
    """Attach its allowed range to each design option of ``parser``: the lengths
    (LIMITS_MM, by the option's dest) and the layers' stiffness scales."""
    for action in parser._actions:  # noqa: SLF001 - argparse keeps its options there
        if action.dest in LIMITS_MM:
            number_action(action, *LIMITS_MM[action.dest], "mm")
        elif action.dest.endswith("_stiffness_scale"):
            number_action(action, *STIFFNESS_SCALE_LIMITS)
