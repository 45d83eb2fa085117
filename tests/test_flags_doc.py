"""Every validity flag the code can raise is in docs/service.md's table of flags, with
its meaning: a script that tests ``validity["flags"]`` can look each one up."""

from __future__ import annotations

import re
from pathlib import Path

from surrogate.calibration._saved_design import UNSEALED_FLAG
from surrogate.emulator.stretch_hazard import FLAG as STRETCH_FLAG
from surrogate.predictor import FILE_FLAGS, POINT_FLAGS
from surrogate.volume_control import LONGEST_TIME_FLAG

ROOT = Path(__file__).resolve().parents[1]
DOC = (ROOT / "docs" / "service.md").read_text()
TABLE = DOC[DOC.index("## Validity flags"):DOC.index("## Errors")]
# a flag put in a list of flags: appended, inserted, or a list's first
RAISED = re.compile(r"""(?:flags"?\]?\.(?:append|insert)\((?:\d+,\s*)?|"flags":\s*\[|"""
                    r"""flags\s*=\s*\[)\s*"([a-z][a-z0-9_]+)\"""")
# a flag returned with its message, for the caller to append (emulator.validity.undercover)
RETURNED = re.compile(r"""return \("([a-z][a-z0-9_]+)",\s*\n\s*f"on FE curves""")


def raised_in_code() -> set[str]:
    found: set[str] = set()
    for pkg in ("surrogate", "service"):
        for path in (ROOT / pkg).rglob("*.py"):
            text = path.read_text()
            found |= set(RAISED.findall(text)) | set(RETURNED.findall(text))
    return found


def documented() -> set[str]:
    """The names in the table's first column."""
    return {name for cell in re.findall(r"^\| (.+?) \|", TABLE, re.M)
            for name in re.findall(r"`([A-Za-z<][A-Za-z0-9_<>]+)`", cell)}


def test_the_code_raises_flags_the_pattern_finds():
    found = raised_in_code()
    # the pattern finds the literal flags of the emulator, the exponential model, the
    # calibrated models and the pump view (a guard: an empty set would pass anything)
    assert {"past_fe_range", "force_band_too_wide", "near_stiffness_balance",
            "two_balloon_regime", "pressure_outside_calibration",
            "pressures_look_like_kpa", "band_undercovers_random_designs"} <= found


def test_every_flag_the_code_raises_is_in_the_table():
    named = documented()
    flags = (raised_in_code() | POINT_FLAGS | FILE_FLAGS
             | {STRETCH_FLAG, LONGEST_TIME_FLAG, UNSEALED_FLAG})
    missing = sorted(f for f in flags if f not in named)
    assert not missing, f"flags not in docs/service.md's table: {missing}"
    # the fields' own flags, made from the field's name
    assert "<field>_outside_calibration" in named
    assert {"L_outside_fitted_range", "t_outside_fitted_range"} <= named
