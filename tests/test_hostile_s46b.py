"""The forty-sixth session's hostile-input audit, its small leftovers (after
tests/test_hostile_s46.py): a number whose text a float does not hold (1e-400) refused as
written, not as "got 0.0"; an empty item of a list option named with the option's range; a
grid's integer setting given a float told the setting's range; a CSV data file's cells held
to the JSON file's rule of 200 characters; the explorer's number boxes never showing another
number than the one typed (1e-300 as "0").

Each test failed on the code before its fix (commit messages say which), bar the guards.
"""

from __future__ import annotations

import pickle
import textwrap
from pathlib import Path

import pytest
from test_cli_fuzz import run, visible_lines
from test_hostile_s46 import server  # noqa: F401 - its live server, the fixture of part 5

# -- 1. a number the float does not hold is refused as written --------------------------------

DESIGN = ["--L-mm", "7.1", "--t-mm", "0.5"]


UNHELD = "does not fit a 64-bit float (sizes about 5e-324 to 1.8e308, or 0): it would be read as"


@pytest.mark.parametrize(("argv", "words"), [    # the parser's words since the forty-eighth
    (["predict", "--L-mm", "1e-400", "--t-mm", "0.5", "--pressures", "1000"],    # session
     f"--L-mm: 1e-400 {UNHELD} 0 (allowed: 0.5 to 60 mm)"),
    (["predict", "--L-mm", "-1E400", "--t-mm", "0.5", "--pressures", "1000"],
     f"--L-mm: -1E400 {UNHELD} -inf (allowed: 0.5 to 60 mm)"),
    (["predict", *DESIGN, "--T-mm", "1e-400", "--pressures", "1000"],
     f"--T-mm: 1e-400 {UNHELD} 0 (allowed: 0.1 to 10 mm)"),
    (["predict", *DESIGN, "--body-stiffness-scale", "1e-400", "--pressures", "1000"],
     f"--body-stiffness-scale: 1e-400 {UNHELD} 0 (allowed: 0.01 to 100)"),
    (["predict", *DESIGN, "--pressures", "1000", "--inlet", "--flow-ul-s", "1",
      "--viscosity-pa-s", "1e-400"],
     f"--viscosity-pa-s: 1e-400 {UNHELD} 0 (allowed: viscosity 0.0001 to 100 Pa s)"),
    (["solve", "--L-mm", "7.1", "--t-mm", "1e-400"],
     f"--t-mm: 1e-400 {UNHELD} 0 (allowed: 0.05 to 5 mm)"),
    (["solve", *DESIGN, "--max-pressure-pa", "1e-400"],
     f"--max-pressure-pa: 1e-400 {UNHELD} 0 (allowed: 1 to 1e+07 Pa)"),
])
def test_a_number_the_float_does_not_hold_is_refused_as_written(argv, words, monkeypatch):
    """`--L-mm 1e-400` said "got 0.0" (the text underflows), `--L-mm -1e400` "got -inf":
    a different number from the one typed. Shown as written now, with the range (by the
    parser since the forty-eighth session, as a list option's and a JSON body's)."""
    import solver

    monkeypatch.setattr(solver, "solve", lambda *a, **k: pytest.fail("a solve started"))
    code, _, err, escaped = run(argv)
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1, err
    assert words in lines[0], lines[0]


def test_a_written_number_is_the_floats_value():
    """Guard: a WrittenNumber is the float's value in every computation and in a
    pickle (a worker process), and a number the float holds stays a plain float."""
    from solver.number_text import WrittenNumber, ascii_float

    tiny = ascii_float(" 1e-400 ")
    assert isinstance(tiny, WrittenNumber) and tiny == 0.0 and f"{tiny:.2f}" == "0.00"
    assert repr(tiny) == "1e-400" and f"{tiny:g}" == "1e-400"
    assert repr(pickle.loads(pickle.dumps(tiny))) == "1e-400"
    for text in ("0", "0.0", "-0e5", "1e-300", "inf", "2.5"):
        assert type(ascii_float(text)) is float, text


def test_a_tiny_pressure_in_range_is_refused_as_written():
    """1e-400 Pa was answered as 0 Pa (inside 0..20000 Pa) until the forty-seventh session:
    a list item the float does not hold is now refused as written, as a JSON body's is
    (tests/test_hostile_s47.py)."""
    code, out, err, escaped = run(["predict", "--model", "paper", *DESIGN,
                                   "--pressures", "1e-400", "500"])
    assert code == 2 and escaped is None, err
    assert "item 1: 1e-400 does not fit a 64-bit float" in err
    assert "allowed: 0 to 20000 Pa" in err


# -- 2. an empty item of a list option -------------------------------------------------------

@pytest.mark.parametrize(("argv", "words", "allowed"), [
    (["predict", "--model", "paper", *DESIGN, "--pressures", "1,,2"],
     "'1,,2' is not a list of numbers (item 2 is an empty place", "allowed: 0 to 20000 Pa)"),
    (["predict", "--model", "paper", *DESIGN, "--pressures", "100,200 300,,400"],
     "(item 4 is an empty place", "allowed: 0 to 20000 Pa)"),
    (["predict", "--model", "paper", *DESIGN, "--pressures", ",,500"],
     "(item 1 is an empty place", "allowed: 0 to 20000 Pa)"),
    (["inverse", *DESIGN, "--angles-deg", "10,20,,"],
     "(item 3 is an empty place", "allowed: -360 to 360 deg)"),
])
def test_an_empty_item_of_a_list_is_named_with_the_range(argv, words, allowed):
    """`--pressures 1,,2` said "has an empty place between two commas" but neither which
    item nor the range other list errors state."""
    code, _, err, escaped = run(argv)
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1, err
    assert f"argument {argv[-2]}: " in lines[0] and words in lines[0], lines[0]
    assert allowed in lines[0], lines[0]


# -- 3. a grid's integer setting given a float -----------------------------------------------

@pytest.mark.parametrize(("setting", "value"), [("mesh_level", "1.5"), ("max_steps", "2.5"),
                                                ("max_newton_iter", "true")])
def test_an_integer_setting_given_a_float_is_told_its_range(tmp_path, setting, value):
    """`mesh_level = 1.5` in a grid said "(allowed: an integer)": no range. The range
    from the one table of the settings' limits (SETTING_RANGES) now."""
    from solver.settings import SETTING_RANGES

    grid = tmp_path / "g.toml"
    grid.write_text(textwrap.dedent(f"""\
        pairs = [["pdms_1_10", "ecoflex_00_30"]]
        L_mm = [7.1]
        t_mm = [0.5]
        [settings]
        {setting} = {value}
        """))
    code, _, err, escaped = run(["precompute", str(grid), "--db", str(tmp_path / "c.h5"),
                                 "--dry-run"])
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1, err
    lo, hi = SETTING_RANGES[setting]
    assert f"(allowed: an integer {lo} <= {setting} <= {hi})" in lines[0], lines[0]
    assert "line 5" in lines[0], lines[0]


def test_settings_from_plain_data_say_the_range_too():
    from solver.errors import InputError
    from solver.settings import MAX_MESH_LEVEL, settings_from_dict

    with pytest.raises(InputError) as info:
        settings_from_dict({"mesh_level": 1.5})
    assert info.value.allowed == f"an integer 0 <= mesh_level <= {MAX_MESH_LEVEL}"


# -- 4. a CSV file's cells held to the rule of a JSON file's ---------------------------------

EXAMPLE_CSV = (Path(__file__).resolve().parents[1]
               / "surrogate/calibration/data/example_lab.csv")


@pytest.mark.parametrize("column", ["curve_id", "body_material", "membrane_material"])
@pytest.mark.parametrize("suffix", [".csv", ".json"])
def test_a_long_text_cell_is_refused_alike_in_csv_and_json(tmp_path, column, suffix):
    """A CSV curve_id or material of 10,000 characters was taken (or named as an unknown
    material), where the same cell in a JSON file (and POST /v1/calibrate) is refused at
    200 characters. One rule for both (surrogate.measured_cell), naming row and column."""
    import csv
    import io
    import json

    lines = [x for x in EXAMPLE_CSV.read_text().splitlines() if not x.startswith("#")]
    rows = list(csv.DictReader(lines))
    rows[3][column] = "s" * 10_000
    path = tmp_path / f"lab{suffix}"
    if suffix == ".json":
        path.write_text(json.dumps(rows))
    else:
        out = io.StringIO()
        writer = csv.DictWriter(out, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
        path.write_text(out.getvalue())
    code, _, err, escaped = run(["calibrate", str(path), "--report", str(tmp_path / "r.json")])
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1, err
    assert f"{column}: row 4: text of 10000 characters (at most 200)" in lines[0], lines[0]
    assert "(allowed: a finite number (|value| <= 1e15), text (at most 200" in lines[0]


# -- 5. the explorer's number boxes show the number the user typed ---------------------------

@pytest.mark.timeout(300)
def test_a_number_box_never_shows_another_number(watched, server):  # noqa: F811
    """A stiffness scale of 1e-300, shown again when the width changed (every design box
    is redrawn), read "0": the boxes showed values rounded to 1e-4 whatever they were
    (1e305 read "Infinity"). To 4 significant digits where rounding to 1e-4 is off by
    more than 1 % now."""
    from explorer_browser import change, open_explorer

    page = open_explorer(watched, server.url)
    page.fill("#body_scale", "1e-300")
    change(page, "#W_mm", "4")
    page.wait_for_function("document.getElementById('L_mm').value !== '7.1'")
    assert page.input_value("#body_scale") == "1e-300"
    assert page.input_value("#L_mm") == str(round(7.1 * 4 / 3, 4))  # lengths still to 0.1 um
    shown = page.evaluate("import('/static/explorer/js/design.js').then((m) => "
                          "[1e305, 0.00015, 1.234567e-300, 7.123456, 0.0333333, 0, 2.5]"
                          ".map(m.shown))")
    assert shown == ["1e+305", "0.00015", "1.235e-300", "7.1235", "0.0333", "0", "2.5"], shown
