"""The forty-eighth session's hostile-input audit, round nine (after tests/test_hostile_s47.py):
a single command-line option's number that a float does not hold (``--tubing-mm 1e-400
0.5``: tubing 0 mm long) refused as written with the option's range, as a list option's
and a JSON body's already were.

Each test failed on the code before its fix (commit messages say which), bar the guards.
"""

from __future__ import annotations

import argparse

import pytest
from test_cli_fuzz import run, visible_lines

# -- 1. a single option's number the float does not hold --------------------------------------

DESIGN = ["--L-mm", "7.1", "--t-mm", "0.5"]
UNHELD = "does not fit a 64-bit float (sizes about 5e-324 to 1.8e308, or 0): it would be read as"


@pytest.mark.parametrize(("argv", "words"), [
    # each a range that holds 0: the value was taken as 0 and answered (or solved)
    (["predict", "--model", "paper", *DESIGN, "--pressures", "1000", "--inlet",
      "--flow-ul-s", "1", "--tubing-mm", "1e-400", "0.5"],
     f"--tubing-mm: 1e-400 {UNHELD} 0 (allowed: LENGTH 0 to 100000, BORE 0.05 to 20 mm)"),
    (["predict", "--model", "paper", *DESIGN, "--pressure-range", "1e-400", "2000", "5"],
     f"--pressure-range: 1e-400 {UNHELD} 0 (allowed: 0 <= START, STOP <= 20000 Pa; "
     "NUM an integer 1..100000)"),
    (["solve", "--spring-k-n-per-m", "1e-400"],
     f"--spring-k-n-per-m: 1e-400 {UNHELD} 0 (allowed: 0 to 1e+06 N/m)"),
    # ranges without 0: a later check said "got 1e-400"; the parser's words now, one rule
    (["inverse", "--angle-deg", "30", "--pressure-pa", "-1e-400"],
     f"--pressure-pa: -1e-400 {UNHELD} 0 (allowed: 0 < pressure <= 1e+06 Pa)"),
    (["fit", "--db", "x.h5", "-o", "y.json", "--level", "1e-400"],
     f"--level: 1e-400 {UNHELD} 0 (allowed: 0.5 <= level < 1)"),
])
def test_a_single_options_number_the_float_does_not_hold_is_refused_as_written(
        argv, words, monkeypatch):
    """`--tubing-mm 1e-400 0.5` was answered with tubing 0 mm long, `--pressure-range
    1e-400 2000 5` from 0 Pa, `solve --spring-k-n-per-m 1e-400` solved a free tip: each a
    different number from the one typed, where `--pressures 1e-400` and a JSON body's
    1e-400 are refused. Refused as written by the parser now, with the option's range."""
    import solver

    monkeypatch.setattr(solver, "solve", lambda *a, **k: pytest.fail("a solve started"))
    code, out, err, escaped = run(argv)
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1 and not out, (err, out)
    assert words in lines[0], lines[0]


def test_every_number_option_carries_its_range():
    """Guard: every float option of every command has its allowed range attached, so a
    word the parser refuses (``abc``, ``1e-400``) is told the range, not only the form."""
    from service.cli import build_parser

    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    missing = [f"{name} {'/'.join(a.option_strings)}"
               for name, command in commands.choices.items() for a in command._actions
               if a.type is float and not getattr(a, "allowed", None)]
    assert not missing


def test_a_single_options_number_the_float_holds_is_read_as_before():
    """Guard: 0, a tiny number a float holds and 1e308 read as written (ranges decide)."""
    code, out, err, _ = run(["predict", "--model", "paper", *DESIGN,
                             "--pressure-range", "0", "1e-300", "2"])
    assert code == 0 and "0.000" in out, err
