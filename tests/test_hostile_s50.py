"""The fiftieth session's hostile-input audit, round eleven (after tests/test_hostile_s49.py):
round ten's leftovers (Excel's ``sep=;`` line read, a database filter outside its field's
range refused, one limit for a pressure list however it is asked, a grid file's size
bounded before its TOML is parsed, a material pair's one message) and what was found
after them.

Each test failed on the code before its fix (commit messages say which), bar the guards.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest
from test_cli_fuzz import run, visible_lines

DATA = Path(__file__).parent / "data"
ROOT = Path(__file__).resolve().parents[1]

# -- 1. Excel's 'sep=;' line above the header ---------------------------------------------------


def _with_first_line(tmp_path, name: str, first: str, *, suffix: str = "\n",
                     encoding: str = "utf-8") -> Path:
    """A test data file with ``first`` written above its header (comments dropped)."""
    lines = [line for line in (DATA / name).read_text(encoding="utf-8").splitlines()
             if not line.startswith("#")]
    path = tmp_path / "export.csv"
    path.write_text(first + suffix + "\n".join(lines) + "\n", encoding=encoding)
    return path


@pytest.mark.parametrize(("name", "first", "encoding"), [
    ("lab_gauge_noise_body_stiffer.csv", "sep=;", "utf-8"),
    ("lab_gauge_noise_body_stiffer.csv", "SEP=;", "utf-8-sig"),      # with a BOM
    ("lab_gauge_noise_body_stiffer.csv", '"sep=;";;;', "utf-16"),    # quoted, as a row
    ("lab_gauge_noise_air_tilt_two_flows_rad.csv", "sep=,", "utf-8"),
])
def test_an_excel_sep_line_names_the_separator_and_is_not_data(tmp_path, name, first,
                                                                encoding):
    """A first line `sep=;` (Excel's hint; labs' exports write it) was refused as "text
    above the header": it is read as the separator it names, the rows the same as
    without it."""
    from surrogate.calibration import load_observations

    plain = load_observations(_with_first_line(tmp_path, name, "", suffix=""))
    hinted = load_observations(_with_first_line(tmp_path, name, first, encoding=encoding))
    assert hinted.sha256 == plain.sha256 and hinted.n == plain.n


def test_a_tab_named_by_sep_is_read(tmp_path):
    from surrogate.calibration import load_observations

    semi = _with_first_line(tmp_path, "lab_gauge_noise_body_stiffer.csv", "", suffix="")
    plain = load_observations(semi)
    tabbed = tmp_path / "tabs.csv"
    tabbed.write_text("sep=\t\n" + semi.read_text(encoding="utf-8").replace(";", "\t"),
                      encoding="utf-8")
    assert load_observations(tabbed).sha256 == plain.sha256


@pytest.mark.parametrize(("first", "words"), [
    ("sep=|", "header: the first line 'sep=|' names '|' as the field separator (allowed: "
              "sep=, sep=; or sep= and a tab (',', ';', a tab), or no sep= line)"),
    ("sep=", "header: the first line 'sep=' names '' as the field separator"),
])
def test_a_sep_line_naming_another_separator_is_told_which_it_may_name(tmp_path, first, words):
    path = _with_first_line(tmp_path, "lab_gauge_noise_body_stiffer.csv", first)
    code, out, err, escaped = run(["calibrate", str(path), "--report", str(tmp_path / "r.json")])
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1, err
    assert words in lines[0], lines[0]


def _csv_js(tmp_path, body: str) -> list:
    """What a node script of ``body`` pushes onto ``out``, with the explorer's
    js/csv.js imported."""
    script = tmp_path / "probe.mjs"
    script.write_text(
        f'import {{ decodeMeasured, parseCsv }} from '
        f'"{(ROOT / "service/static/explorer/js/csv.js").as_uri()}";\n'
        f'const out = [];\n{body}console.log(JSON.stringify(out));\n', encoding="utf-8")
    done = subprocess.run(["node", str(script)], capture_output=True, text=True, timeout=60,
                          check=True)
    return json.loads(done.stdout)


@pytest.mark.skipif(shutil.which("node") is None, reason="node is not installed")
def test_the_explorer_reads_a_sep_line_as_the_server_does(tmp_path):
    """The page's CSV reader (js/csv.js) sent the `sep=;` line as the header."""
    rows_semi, rows_tab, refusal, after = _csv_js(tmp_path, (
        'out.push(parseCsv("\\uFEFFsep=;\\r\\ncurve_id;pressure_pa;angle_deg\\r\\nc;1,5;2\\r\\n"));\n'
        'out.push(parseCsv("sep=\\t\\ncurve_id\\tpressure_pa\\nc\\t2,5\\n"));\n'
        'try { parseCsv("sep=|\\na|b\\n"); } catch (e) { out.push(e.message); }\n'
        'try { parseCsv("sep=;\\ncurve_id;pressure_pa\\nc;1\\nend of log;\\n"); }\n'
        'catch (e) { out.push(e.message); }\n'))
    assert rows_semi == [{"curve_id": "c", "pressure_pa": 1.5, "angle_deg": 2}]
    assert rows_tab == [{"curve_id": "c", "pressure_pa": 2.5}]
    assert "names '|' as the field separator" in refusal
    # the sep= line counts as a line of the file in the page's line numbers too
    assert after.startswith("line 4 holds text after the last reading ('end of log')"), after


# -- 2. a database filter outside its field's range ----------------------------------------------

SHIPPED_DB = str(ROOT / "service" / "data" / "curves.h5")


@pytest.mark.parametrize(("where", "words"), [
    ("L_mm=1e-400", "--where L_mm: 1e-400 is outside the lengths a design may have "
                    "(allowed: 0.5 <= L_mm <= 60 (mm))"),
    ("L_mm=0.1", "--where L_mm: 0.1 is outside the lengths a design may have "
                 "(allowed: 0.5 <= L_mm <= 60 (mm))"),
    ("t_mm=99", "--where t_mm: 99 is outside the lengths a design may have "
                "(allowed: 0.05 <= t_mm <= 5 (mm))"),
])
def test_a_filter_no_design_can_have_is_refused_with_the_fields_range(where, words):
    """`db ls --where L_mm=1e-400` (or 0.1, outside the box) listed "0 records": the value
    is refused with the design check's range (solver.design.LIMITS_MM), as
    GET /v1/curves refuses it."""
    code, out, err, escaped = run(["db", "ls", SHIPPED_DB, "--where", where])
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1 and not out, err
    assert words in lines[0], lines[0]


def test_a_filter_in_range_that_no_record_has_still_lists_none():
    """Guard: a length in range that no record has is "0 records", with what they hold."""
    code, out, err, escaped = run(["db", "ls", SHIPPED_DB, "--where", "L_mm=60"])
    assert code == 0 and escaped is None, err
    assert "0 records; no record has L_mm 60" in err


# -- 3. one limit on the pressures asked, however they are asked --------------------------------

PAPER = ["--model", "paper", "--L-mm", "7.1", "--t-mm", "0.5"]


def test_a_pressure_range_takes_as_many_pressures_as_a_list():
    """`--pressure-range 0 2000 100000` was answered (100,000 rows) where `--pressures`
    and POST /v1/predict's `pressures_pa` take 1000 values: one limit,
    surrogate.predictor.MAX_ASKED_VALUES."""
    from surrogate.predictor import MAX_ASKED_VALUES

    code, out, err, escaped = run(["predict", *PAPER, "--pressure-range", "0", "2000",
                                   str(MAX_ASKED_VALUES + 1)])
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1 and not out, err
    assert (f"--pressure-range: START = 0, STOP = 2000, NUM = {MAX_ASKED_VALUES + 1} "
            f"(allowed: 0 <= START, STOP <= 20000 Pa; NUM an integer 1..{MAX_ASKED_VALUES}, "
            "as --pressures' values)") in lines[0], lines[0]
    code, out, err, escaped = run(["predict", *PAPER, "--pressure-range", "0", "2000",
                                   str(MAX_ASKED_VALUES), "--json"])
    assert code == 0 and escaped is None, err
    assert len(json.loads(out)["angle_deg"]) == MAX_ASKED_VALUES


# -- 4. a grid file's size, before its TOML is parsed --------------------------------------------


def test_a_grid_file_past_one_mib_is_refused_before_it_is_parsed(tmp_path, monkeypatch):
    """A 16 MiB grid of unknown keys cost tomllib's parse (5-15 s, 440 MB) to refuse: a grid
    file is held to 1 MiB (the shipped ones are 1-9 kB), refused before tomllib sees it."""
    import tomllib

    path = tmp_path / "big.toml"
    path.write_text("".join(f"k{i:07d} = 1\n" for i in range(2**20 // 13 + 1)),
                    encoding="utf-8")

    def never(*args, **kwargs):
        raise AssertionError("the grid's TOML was parsed")

    monkeypatch.setattr(tomllib, "loads", never)
    code, out, err, escaped = run(["precompute", str(path), "--db", str(tmp_path / "x.h5"),
                                   "--dry-run"])
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1, err
    assert ("big.toml: larger than 1 MiB (allowed: a grid file (TOML: ranges, lists and "
            "[[sample]] tables) of at most 1 MiB)") in lines[0], lines[0]
    assert not (tmp_path / "x.h5").exists()


def test_the_shipped_grids_are_far_below_the_limit():
    """Guard: the limit is over 100 times the largest shipped grid."""
    from solver.precompute.grid import MAX_GRID_BYTES

    assert max(p.stat().st_size for p in (ROOT / "grids").glob("*.toml")) * 100 < MAX_GRID_BYTES


# -- 5. an item of a list told its own form, not its list's size ---------------------------------


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    """The app without models: nothing here reaches them."""
    from fastapi.testclient import TestClient
    from service_fakes import settings_for

    from service.app import create_app

    with TestClient(create_app(settings_for(tmp_path_factory.mktemp("s50")))) as c:
        yield c


PAIR_FORMS = ('the text "body/membrane" (e.g. "pdms_1_10/ecoflex_00_30"), or an object of '
              "body_material, membrane_material")
TARGET = {"kind": "angle_at_pressure", "pressure_pa": 1500, "angle_deg": 45}


@pytest.mark.parametrize(("item", "message"), [
    # was "'x/y/z' is not body/membrane (e.g. ...)" beside "allowed: 1-20 values"
    ("x/y/z", "'x/y/z' is not of this form"),
    # a 5000-character text was echoed whole in the message
    ("a/" * 2500, "'" + "a/" * 18 + "... is not of this form"),
    # was told "a JSON object of body_material, membrane_material": the text form too
    (5, "Input should be a valid dictionary or object to extract fields from"),
])
def test_a_material_pair_item_is_told_its_forms_once(client, item, message):
    from service_fakes import assert_problem

    problem = assert_problem(client.post("/v1/inverse", json={
        "target": TARGET, "material_pairs": ["pdms_1_10/ecoflex_00_30", item]}), 422,
        "material_pairs.1")
    error = next(e for e in problem["errors"] if e["field"] == "material_pairs.1")
    assert error["message"] == message and error["allowed"] == PAIR_FORMS, error


@pytest.mark.parametrize(("path", "body", "field", "allowed"), [
    ("/v1/predict", {"design": {"L_mm": 7.1, "t_mm": 0.5}, "pressures_pa": [100, -1]},
     "pressures_pa.1", "each 0 <= pressures_pa <= 20000"),
    ("/v1/inverse/pressure", {"design": {"L_mm": 7.1, "t_mm": 0.5}, "angles_deg": [1e9]},
     "angles_deg.0", "each -360 <= angles_deg <= 360"),
])
def test_a_list_item_is_told_the_items_range_alone(client, path, body, field, allowed):
    """An item's error was told "each 0 <= pressures_pa <= 20000; 1-1000 values": its list's
    size is not the item's to change."""
    from service_fakes import assert_problem

    problem = assert_problem(client.post(path, json=body), 422, field)
    assert next(e for e in problem["errors"] if e["field"] == field)["allowed"] == allowed


def test_the_list_itself_is_still_told_its_size(client):
    """Guard: the list's own error keeps its number of values."""
    from service_fakes import assert_problem

    problem = assert_problem(client.post("/v1/inverse", json={
        "target": TARGET, "material_pairs": []}), 422, "material_pairs")
    assert problem["errors"][0]["allowed"] == "1-20 values"


# -- 6. a grid file as Windows and old Mac editors save it ---------------------------------------

GRID = 'pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = [7.1, 9.1]\nt_mm = 0.5\n'


@pytest.mark.parametrize(("encoding", "newline"), [
    ("utf-8-sig", "\n"),      # Notepad's "UTF-8 with BOM": "Invalid statement (line 1, col 1)"
    ("utf-16", "\r\n"),       # Notepad's "Unicode": "byte 0xff at offset 0 is not UTF-8"
    ("utf-8", "\r"),          # a CR alone: "line 3: Expected newline ... (line 1, column 41)"
])
def test_a_grid_saved_with_a_byte_order_mark_or_cr_line_ends_is_read(tmp_path, encoding,
                                                                     newline):
    from solver.precompute import load_grid

    path = tmp_path / "grid.toml"
    path.write_bytes(GRID.replace("\n", newline).encode(encoding))
    grid = load_grid(path)
    assert sorted(p.design.L_mm for p in grid.points) == [7.1, 9.1]


def test_a_grid_in_latin_1_is_still_refused_naming_utf_8(tmp_path):
    """Guard: without a mark a grid is UTF-8; a latin-1 degree sign is named."""
    from solver.precompute import GridError, load_grid

    path = tmp_path / "grid.toml"
    path.write_bytes(('description = "90°"\n' + GRID).encode("latin-1"))
    with pytest.raises(GridError, match=r"line 1: encoding: byte 0xb0 at offset 17 is not "
                                        r"UTF-8 \(allowed: a UTF-8 text file"):
        load_grid(path)


# -- 7. a grid's integer past what Python converts or a float holds ------------------------------

UNHELD = "does not fit a 64-bit float (sizes about 5e-324 to 1.8e308, or 0): it would be read as"


@pytest.mark.parametrize(("body", "words"), [
    # tomllib's ValueError "Exceeds the limit (4300 digits)" escaped as a traceback
    ("L_mm = {start = 4.1, stop = 5.1, num = " + "9" * 5000 + "}\n",
     "line 3: toml: an integer of more than 4300 digits, past any value a grid takes "
     "(allowed: an integer 1 <= num <= 100000; lengths in mm"),
    # an integer a float does not hold: OverflowError where it was used (or when echoed)
    ("L_mm = " + "9" * 4000 + "\n",
     f"line 3: L_mm: 99999999999999999999... (4000 characters) {UNHELD} inf "
     "(allowed: 0.5 <= L_mm <= 60 (mm))"),
    ("L_mm = {start = 4.1, stop = 5.1, num = 0x" + "f" * 5000 + "}\n",
     f"line 3: L_mm.num: 0xffffffffffffffffff... (5002 characters) {UNHELD} inf "
     "(allowed: an integer 1 <= num <= 100000)"),
    ("L_mm = 7.1\n[materials.soft]\nmu_kpa = [-" + "9" * 4000 + "]\nalpha = [2.0]\n",
     f"line 5: materials.soft.mu_kpa.0: -9999999999999999999... (4001 characters) {UNHELD} "
     "-inf"),
    ("L_mm = 7.1\n[settings]\nmax_pressure_pa = " + "9" * 4000 + "\n",
     f"line 5: settings.max_pressure_pa: 99999999999999999999... (4000 characters) {UNHELD} "
     "inf (allowed: a number 1.0 <= max_pressure_pa <= 10000000.0)"),
])
def test_a_grid_integer_too_long_to_use_is_one_line_naming_it(tmp_path, body, words):
    path = tmp_path / "grid.toml"
    path.write_text('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nt_mm = 0.5\n' + body,
                    encoding="utf-8")
    code, out, err, escaped = run(["precompute", str(path), "--db", str(tmp_path / "x.h5"),
                                   "--dry-run"])
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1, (err, escaped)
    assert words in lines[0], lines[0]


# -- 8. a database filter's echo -----------------------------------------------------------------


def test_a_filter_that_meets_nothing_is_not_echoed_whole():
    """`db ls --where body_material=<5000 characters>` printed them all on its "0 records"
    line: cut as an error line cuts a word (service.cli.shown)."""
    code, out, err, escaped = run(["db", "ls", SHIPPED_DB, "--where",
                                   "body_material=" + "x" * 5000])
    assert code == 0 and escaped is None, err
    assert len(err) < 400 and "(5002 characters)" in err, err[:500]


# -- 9. an API key no client could send -----------------------------------------------------------


@pytest.mark.parametrize(("key", "words"), [
    ("", "BALLOON_API_KEY: is empty (or spaces only): no client could send it"),
    ("   ", "BALLOON_API_KEY: is empty (or spaces only): no client could send it"),
    ("s3cret-key ", "BALLOON_API_KEY: begins or ends with a space or tab"),
    ("s3cret\x07key", "BALLOON_API_KEY: holds a control character"),
])
def test_an_api_key_no_header_can_carry_is_refused_at_start_up(monkeypatch, key, words):
    """`BALLOON_API_KEY=` (a compose file's unset ${KEY}) or a key ending in a space started
    a server that refused every mutating request, the health "ok": refused at start-up,
    naming the variable, never echoing the key."""
    from service.settings import settings_from_environment
    from solver.errors import InputError

    monkeypatch.setenv("BALLOON_API_KEY", key)
    with pytest.raises(InputError) as info:
        settings_from_environment()
    text = str(info.value)
    assert text.startswith(words) and "(allowed: unset (the mutating endpoints off)" in text
    assert "s3cret" not in text


def test_a_key_with_a_tab_inside_is_taken(monkeypatch):
    """Guard: a header's value may hold a tab between its characters."""
    from service.settings import settings_from_environment

    monkeypatch.setenv("BALLOON_API_KEY", "one\ttwo")
    assert settings_from_environment().api_key.get_secret_value() == "one\ttwo"


# -- 10. a target's subnormal value, refused in words that allow it -------------------------------


@pytest.mark.parametrize(("target", "field", "got"), [
    ({"kind": "angle_at_pressure", "pressure_pa": 5e-324, "angle_deg": 45}, "target.pressure_pa",
     "got 5e-324, below the smallest normal float (2.23e-308): counted as 0 "
     "(allowed: 0 < pressure_pa <= 20000 Pa)"),
    ({"kind": "angle_at_time", "time_s": 5e-324, "flow_ul_s": 1, "angle_deg": 45},
     "target.time_s", "got 5e-324, below the smallest normal float (2.23e-308): counted as 0"),
    ({"kind": "force_at_pressure", "pressure_pa": 1500, "force_mn": -1e-310},
     "target.force_mn", "got -1e-310, below the smallest normal float (2.23e-308): counted "
                        "as 0 (allowed: 0 < |force_mn| <= 10000 mN"),
])
def test_a_subnormal_target_is_told_it_counts_as_zero(client, target, field, got):
    """`pressure_pa: 5e-324` was refused "got 5e-324 (allowed: 0 < pressure_pa <= 20000
    Pa)": a value the words allow. The search counts a subnormal as 0 (its arithmetic
    overflows); the refusal says so."""
    from service_fakes import assert_problem

    problem = assert_problem(client.post("/v1/inverse", json={"target": target,
                                                             "model": "paper"}), 422, field)
    assert got in problem["detail"], problem["detail"]


# -- 11. two writers at one new database: salvage and another -------------------------------------


@pytest.mark.parametrize("other_still_writing", [True, False])
def test_salvage_never_removes_or_fills_a_database_made_while_it_read(
        tmp_path, monkeypatch, other_still_writing):
    """`db salvage DB -o NEW` checks NEW does not exist, reads DB (39 s for the shipped
    file), then wrote NEW: a database another process made at NEW meanwhile (a second
    salvage, a precompute job) was deleted when its writer still held it (the busy error
    unlinked NEW) or written into when it had finished. NEW is now written under a
    staging name and linked into place only if nothing is there."""
    from test_store import record_for

    import solver.store.salvage as salvage_module
    from solver.store import CurveStore
    from solver.store.salvage import salvage

    source, target = tmp_path / "old.h5", tmp_path / "new.h5"
    with CurveStore(source, mode="a") as db:
        db.put_many([record_for(L_mm=L) for L in (4.1, 5.1)])
    theirs = record_for(L_mm=9.1)
    other: list[CurveStore] = []
    reading = salvage_module._read_intact

    def read_while_another_writes(db):
        writer = CurveStore(target, mode="a")
        writer.put(theirs)
        if other_still_writing:
            other.append(writer)
        else:
            writer.close()
        return reading(db)

    monkeypatch.setattr(salvage_module, "_read_intact", read_while_another_writes)
    try:
        with pytest.raises(Exception, match="new.h5 exists"):
            salvage(source, target)
    finally:
        for writer in other:
            writer.close()
    with CurveStore(target) as db:
        assert [r.key for r in db.records()] == [theirs.key]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new.h5", "old.h5"]  # no staging


# -- 12. the explorer page reads a data file's bytes as the server does ---------------------------


@pytest.mark.skipif(shutil.which("node") is None, reason="node is not installed")
def test_the_explorer_decodes_a_data_file_as_the_server_does(tmp_path):
    """The page read a data file with `file.text()`: UTF-16 with a byte-order mark (Excel's
    "Unicode Text") became NULs and latin-1 "90°" became "90\\uFFFD", sent as rows; the CLI
    reads the first and refuses the second naming its line. `decodeMeasured` does both."""
    rows, refusal = _csv_js(tmp_path, (
        'const text = "curve_id\\tpressure_pa\\tangle_deg\\r\\nc\\t1,5\\t2\\r\\n";\n'
        'const le = Buffer.concat([Buffer.from([0xff, 0xfe]), Buffer.from(text, "utf16le")]);\n'
        'out.push(parseCsv(decodeMeasured(new Uint8Array(le))));\n'
        'try { decodeMeasured(new Uint8Array([0x61, 0x0a, 0x39, 0x30, 0xb0])); }\n'
        'catch (e) { out.push(e.message); }\n'))
    assert rows == [{"curve_id": "c", "pressure_pa": 1.5, "angle_deg": 2}]
    assert refusal.startswith("line 2: not UTF-8 text (latin-1 or Windows-1252"), refusal
    assert "decodeMeasured(new Uint8Array(await file.arrayBuffer()))" in (
        ROOT / "service/static/explorer/js/calibration.js").read_text(encoding="utf-8")


# -- 13. a curve database given as the model ------------------------------------------------------


def test_a_curve_database_given_as_the_model_is_named_as_one():
    """`predict --model service/data/curves.h5` was "not valid JSON ('utf-8' codec can't
    decode byte 0x89 in position 512: invalid start byte)"."""
    code, out, err, escaped = run(["predict", "--model", SHIPPED_DB, "--L-mm", "7.1",
                                   "--t-mm", "0.5", "--pressures", "100"])
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1, err
    assert ("curves.h5: this is an HDF5 file (a curve database?), not a model file (a model "
            "is a JSON file, or a name)") in lines[0], lines[0]


def test_measured_lengths_are_held_to_the_design_limits():
    """A measured row's lengths are checked as a design's are (solver.design.LIMITS_MM):
    L_mm 5e-324 was calibrated against ``paper`` (which takes any L) where every
    FE-based model refused it; now the row is refused with the design's range."""
    from solver.design import LIMITS_MM
    from surrogate.calibration._data import RANGES, observations_from_rows
    from surrogate.calibration._errors import DataError
    for name in ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm"):
        assert RANGES[name][:2] == LIMITS_MM[name]
    row = {"curve_id": "a", "L_mm": 5e-324, "t_mm": 0.5, "body_material": "pdms_1_10",
           "membrane_material": "ecoflex_00_30", "pressure_pa": 1000.0, "angle_deg": 10.0}
    with pytest.raises(DataError, match=r"L_mm.*0\.5 <= L_mm <= 60"):
        observations_from_rows([row, {**row, "pressure_pa": 2000.0, "angle_deg": 20.0}])


def test_a_refused_save_leaves_no_empty_models_directory(tmp_path):
    """``calibrate --save N --models-dir NEW/DIR`` makes the directories before the
    calibration's work (to refuse an unmakeable one at once); when the save is then
    refused, the ones it made and left empty are removed again, deepest first, and
    none that holds something (or existed before) is touched."""
    from service.commands.calibrate import _missing_from, _remove_if_empty
    before = tmp_path / "lab"
    before.mkdir()
    target = before / "new" / "models"
    made = _missing_from(target)
    assert made == [target, before / "new"]
    target.mkdir(parents=True)
    _remove_if_empty(made)
    assert before.is_dir() and not (before / "new").exists()
    assert _missing_from(before) == []
    target.mkdir(parents=True)
    (before / "new" / "notes.txt").write_text("kept")
    _remove_if_empty(made)
    assert not target.exists() and (before / "new" / "notes.txt").read_text() == "kept"


@pytest.mark.slow
def test_cli_a_refused_save_makes_no_directory(tmp_path, capsys):
    """N53 (round eight's gauge zero, tests/data): its calibration is not saveable (the
    gauge left above its floor as written); --save into a new directory is refused and
    leaves no directory behind."""
    from pathlib import Path

    from service.cli import main
    data = Path(__file__).parent / "data" / "lab_gauge_noise_gauge_zero_small_tabs.csv"
    models = tmp_path / "new" / "models"
    code = main(["calibrate", str(data), "--report", str(tmp_path / "r.json"),
                 "--save", "n53", "--models-dir", str(models)])
    assert code != 0
    assert "--save" in capsys.readouterr().err
    assert (tmp_path / "r.json").is_file() and not (tmp_path / "new").exists()
