"""``balloon inverse --designs FILE --angles-deg 45``: a lab's batch of designs in a CSV
answered by one loaded model (service/commands/batch.py). Before it a batch was a loop
over ``balloon inverse``, loading the emulator for every design (~20 s each on the
loaded 2-core VM: 200 designs over an hour), with no row for a refused design, no
progress and no model identity in what it printed.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
from pathlib import Path

import pytest

from service import cli

ROOT = Path(__file__).resolve().parent.parent
EMULATOR = ROOT / "service" / "data" / "emulator.json"

DESIGNS = """name,L_mm,t_mm,T_mm,body_material,membrane_material,note
standard,7.1,0.5,,,,the paper's standard design
short,3.6,0.9,1.2,,,outside the box
typo,9,0.7x,,,,a cell that is no number
stiff,9,0.7,1.2,pdms_1_99,,a material with no preset
scaled,9,0.7,1.2,pdms_1_15,ecoflex_00_30,"a note, with a comma"
"""


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    """The command's exit code, stderr and the rows of its CSV, for DESIGNS at 45 deg."""
    tmp = tmp_path_factory.mktemp("batch")
    (tmp / "designs.csv").write_text(DESIGNS)
    out = tmp / "ranked.csv"
    mp = pytest.MonkeyPatch()
    err = io.StringIO()
    mp.setattr("sys.stderr", err)
    try:
        code = cli.main(["inverse", "--designs", str(tmp / "designs.csv"), "--angles-deg",
                         "45", "-o", str(out)])
    finally:
        mp.undo()
    text = out.read_text()
    return code, err.getvalue(), text, list(csv.DictReader(io.StringIO(text)))


def test_every_row_keeps_its_place_and_a_refused_one_says_why(batch) -> None:
    code, _, _, rows = batch
    assert code == 0
    assert [r["name"] for r in rows] == ["standard", "short", "typo", "stiff", "scaled"]
    errors = {r["name"]: r["error"] for r in rows}
    assert errors["standard"] == errors["scaled"] == ""
    # each names the row's column and what it allows, in one line
    assert errors["short"].startswith("L_mm:") and "4 <= L_mm <= 18 mm" in errors["short"]
    assert errors["typo"].startswith("t_mm:") and "'0.7x' is not a number" in errors["typo"]
    assert errors["stiff"].startswith("body_material:") and "pdms_1_15" in errors["stiff"]
    for name in ("short", "typo", "stiff"):
        row = next(r for r in rows if r["name"] == name)
        assert row["pressure_pa"] == "" and "\n" not in row["error"]
    # the user's own columns are carried as written
    assert rows[4]["note"] == "a note, with a comma"


def test_the_answer_is_the_one_designs_answer(batch, capsys) -> None:
    rows = batch[3]
    assert cli.main(["inverse", "--L-mm", "7.1", "--t-mm", "0.5", "--angles-deg", "45",
                     "--json"]) == 0
    one = json.loads(capsys.readouterr().out)
    standard = rows[0]
    assert float(standard["angle_deg"]) == 45
    for column in ("pressure_pa", "lower_pa", "upper_pa", "volume_ul"):
        assert float(standard[column]) == pytest.approx(one[column][0], rel=1e-5)
    assert standard["in_domain"] == "true"


def test_the_output_names_the_model_file_by_its_checksum(batch) -> None:
    rows = batch[3]
    sha = hashlib.sha256(EMULATOR.read_bytes()).hexdigest()
    for row in rows:
        assert (row["model"], row["model_file"], row["model_sha256"]) == (
            "emulator", "emulator.json", sha)
        assert row["balloon_version"] == cli.package_version()


def test_a_spreadsheet_reads_it_and_progress_goes_to_stderr(batch) -> None:
    _, err, text, rows = batch
    header = text.splitlines()[0].split(",")
    assert header[:7] == ["name", "L_mm", "t_mm", "T_mm", "body_material",
                          "membrane_material", "note"]
    assert header[-5:] == ["error", "model", "model_file", "model_sha256", "balloon_version"]
    assert not text.startswith("#") and "\r" not in text
    for row in rows:           # numbers as '.' decimals a spreadsheet reads, or empty
        for column in ("pressure_pa", "lower_pa", "upper_pa", "volume_ul"):
            assert row[column] == "" or float(row[column]) > 0
    assert "balloon: designs 5/5 (3 refused)" in err
    assert "2 of 5 designs answered; 3 refused" in err


@pytest.mark.parametrize(("designs", "extra", "said"), [
    ("name,L_mm\nA,7\n", [], "no column 't_mm'"),
    ("L_mm,t_mm,T_mn\n7,0.5,1\n", [], "column 'T_mn' is none of the design's"),
    ("L_mm,t_mm,L_mm\n7,0.5,8\n", [], "column 'L_mm' given twice"),
    ("L_mm,t_mm\n", [], "a header and no design"),
    ("L_mm,t_mm\n7,0.5\n", ["--L-mm", "7"], "--L-mm: sets one design"),
    ("L_mm,t_mm\n7,0.5\n", ["--pressure-pa", "1000"], "--pressure-pa: sets a design search"),
    ("L_mm,t_mm\n7,0.5\n", ["--json"], "--json: --designs writes CSV"),
])
def test_a_file_or_flags_that_make_no_batch_are_one_line_before_the_model_loads(
        tmp_path, capsys, monkeypatch, designs, extra, said) -> None:
    monkeypatch.setattr("service.commands.inverse.surrogate_from_args",
                        lambda args: pytest.fail("the model was loaded"))
    path = tmp_path / "designs.csv"
    path.write_text(designs)
    assert cli.main(["inverse", "--designs", str(path), "--angles-deg", "45", *extra]) == 2
    err = capsys.readouterr().err
    assert said in err and len(err.strip().splitlines()) == 1, err


def test_designs_needs_angles_and_o_needs_designs(tmp_path, capsys) -> None:
    path = tmp_path / "designs.csv"
    path.write_text("L_mm,t_mm\n7,0.5\n")
    assert cli.main(["inverse", "--designs", str(path)]) == 2
    assert "--designs: needs --angles-deg" in capsys.readouterr().err
    assert cli.main(["inverse", "--L-mm", "7", "--t-mm", "0.5", "--angles-deg", "45", "-o",
                     str(tmp_path / "x.csv")]) == 2
    assert "-o: writes the CSV of --designs" in capsys.readouterr().err


def test_a_row_whose_cells_do_not_match_the_header_is_not_read_by_position(
        tmp_path, capsys) -> None:
    """"7,1" in a comma-separated file is two cells: the row was answered as L 7, t 1."""
    path = tmp_path / "designs.csv"
    path.write_text("L_mm,t_mm\n7,1,0.5\n9,0.7\n")
    assert cli.main(["inverse", "--designs", str(path), "--angles-deg", "45"]) == 0
    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert rows[0]["pressure_pa"] == "" and rows[0]["error"].startswith(
        "row: 3 cells where the header has 2"), rows[0]
    assert rows[1]["error"] == "" and float(rows[1]["pressure_pa"]) > 0


def test_a_german_excel_file_is_read(tmp_path, capsys) -> None:
    path = tmp_path / "designs.csv"
    path.write_text("\ufeffL_mm;t_mm\n7,1;0,5\n")
    assert cli.main(["inverse", "--designs", str(path), "--angles-deg", "45"]) == 0
    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert rows[0]["L_mm"] == "7.1" and float(rows[0]["pressure_pa"]) == pytest.approx(
        1886.87, abs=0.01)
