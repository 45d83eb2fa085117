"""The forty-fourth session's hostile-input audit, round five (after tests/test_hostile_s43.py):
a flow rate of 0 in measured data and the flow range's one table, a NUL byte in a data
file, numbers written in other digits or with underscores, the time band of a design
listed for a time target near the longest pump time, unphysically soft materials, and the
explorer's flow-rate box holding "1e999".

Each test failed on the code before its fix (commit messages say which).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from explorer_browser import LiveServer, change, open_explorer, screenshot
from service_fakes import assert_problem
from test_cli_fuzz import run, visible_lines

from solver.design_space import STIFFNESS_SCALE_LIMITS
from solver.errors import InputError
from solver.materials import MATERIALS, MIN_MU0_KPA, make_material
from surrogate.calibration._data import RANGES
from surrogate.volume_control import MAX_FLOW_UL_S, MAX_TIME_S, MIN_FLOW_UL_S

DESIGN = {"L_mm": 7.1, "t_mm": 0.5}
CLI_DESIGN = ["--L-mm", "7.1", "--t-mm", "0.5"]
EXAMPLE = Path(__file__).resolve().parents[1] / "surrogate/calibration/data/example_lab.csv"
HEADER = "curve_id,L_mm,t_mm,body_material,membrane_material,pressure_pa,angle_deg,time_s,flow_ul_s"


def lab_rows(flow: float = 2.5) -> list[dict]:
    """Two timed curves of the standard design at one flow rate (4 readings each)."""
    return [{"curve_id": c, **DESIGN, "body_material": "pdms_1_10",
             "membrane_material": "ecoflex_00_30", "pressure_pa": p, "angle_deg": a,
             "time_s": float(i), "flow_ul_s": flow}
            for c in ("s1", "s2")
            for i, (p, a) in enumerate(((0, 0.1), (400, 1.6), (800, 4.8), (1200, 12.0)))]


def lab_csv(tmp_path: Path, flow: str) -> Path:
    path = tmp_path / "lab.csv"
    path.write_text(HEADER + "\n" + "".join(
        f"{r['curve_id']},7.1,0.5,pdms_1_10,ecoflex_00_30,{r['pressure_pa']},{r['angle_deg']},"
        f"{r['time_s']},{flow}\n" for r in lab_rows()))
    return path


def one_line_error(argv: list[str]) -> str:
    """The one stderr line of ``balloon argv`` refusing it (exit 2, nothing escaped)."""
    code, out, err, escaped = run(argv)
    lines = visible_lines(err)
    assert (code, escaped) == (2, None), (code, err)
    assert len(lines) == 1 and lines[0].startswith("balloon"), err
    assert "Traceback" not in err
    return lines[0]


# -- 1. a flow rate of 0, and the flow range's one table -------------------------------------

def test_the_measured_flow_range_is_the_pumps_one():
    """The measured data kept their own flow range (0 <= flow_ul_s <= 1e4) beside the
    syringe pump's (1e-6 to 1000 ul/s, /v1/predict's): one fact, one table."""
    lo, hi, inclusive = RANGES["flow_ul_s"]
    assert (lo, hi, inclusive) == (MIN_FLOW_UL_S, MAX_FLOW_UL_S, True)


@pytest.mark.parametrize("flow", [0.0, 2000.0])
def test_a_calibration_refuses_a_flow_outside_the_pumps_range(shipped_client, flow):
    """``POST /v1/calibrate`` took flow_ul_s 0 (a curve that injected nothing, volume
    0 throughout) with a warning, and 2000 ul/s, which /v1/predict refuses."""
    r = shipped_client.post("/v1/calibrate", json={"rows": lab_rows(flow), "model": "paper"})
    problem = assert_problem(r, 422, "rows.0.flow_ul_s")
    assert "1e-06 <= flow_ul_s <= 1000" in problem["errors"][0]["allowed"]


def test_the_cli_calibration_refuses_a_flow_of_zero(tmp_path):
    line = one_line_error(["calibrate", str(lab_csv(tmp_path, "0")), "--report",
                           str(tmp_path / "r.json"), "--model", "paper"])
    assert "flow_ul_s" in line and "1e-06 <= flow_ul_s <= 1000" in line, line
    assert not (tmp_path / "r.json").exists()


# -- 2. a NUL byte in a data file ------------------------------------------------------------

def with_nul(at_line: int, at_column: int) -> bytes:
    lines = EXAMPLE.read_bytes().split(b"\n")
    text = lines[at_line - 1]
    lines[at_line - 1] = text[:at_column - 1] + b"\x00" + text[at_column - 1:]
    return b"\n".join(lines)


@pytest.mark.parametrize(("line", "column"), [(3, 11), (200, 5)])
def test_a_nul_byte_is_named_where_it_is(tmp_path, line, column):
    """A stray NUL byte in the first 4 kB was "line 3: it looks like UTF-16 without a
    byte-order mark"; past them the file was read, the NUL a row of its own ("body_material:
    row 289: unknown material ''"). Either way: the NUL, its line and column."""
    path = tmp_path / "lab.csv"
    path.write_bytes(with_nul(line, column))
    error = one_line_error(["calibrate", str(path), "--report", str(tmp_path / "r.json"),
                            "--model", "paper"])
    assert f"line {line}, column {column}: a NUL byte" in error, error
    assert "UTF-16" not in error and "material" not in error


def test_utf16_without_its_byte_order_mark_is_still_said_so(tmp_path):
    path = tmp_path / "lab.csv"
    path.write_bytes(EXAMPLE.read_text().encode("utf-16-le"))
    error = one_line_error(["calibrate", str(path), "--report", str(tmp_path / "r.json")])
    assert "UTF-16 without a byte-order mark" in error and "NUL" not in error


# -- 3. numbers: ASCII decimal digits only, on the command line and in a query ---------------

@pytest.mark.parametrize(("argv", "option"), [
    (["predict", *CLI_DESIGN, "--pressures", "١٠٠٠"], "--pressures"),
    (["predict", *CLI_DESIGN, "--pressures", "500,1_000"], "--pressures"),
    (["predict", "--L-mm", "7_1", "--t-mm", "0.5", "--pressures", "1000"], "--L-mm"),
    (["predict", *CLI_DESIGN, "--times", "2", "--flow-ul-s", "２.5"], "--flow-ul-s"),
    (["inverse", *CLI_DESIGN, "--angles-deg", "٤٥"], "--angles-deg"),
    (["inverse", *CLI_DESIGN, "--angles-deg", "45", "--level", "0.9_5"], "--level"),
    (["calibrate", str(EXAMPLE), "--report", "/nonexistent-dir/r.json", "--folds", "٥"],
     "--folds"),
    (["inverse", "--angle-deg", "30", "--pressure-pa", "1200", "-n", "2.0"], "-n"),
    (["db", "ls", "service/data/curves.h5", "--where", "L_mm=7_1"], "--where L_mm")])
def test_the_cli_reads_numbers_as_http_does(argv, option):
    """``--pressures ١٠٠٠`` answered 1000 Pa and ``--L-mm 7_1`` a design of L = 71 mm
    (Python's float reads any script's digits and underscores), numbers a JSON body never
    carries: refused naming the option and the form numbers are written in."""
    line = one_line_error(argv)
    assert option in line, line
    assert "ASCII decimal digits" in line or "not a finite number" in line, line


@pytest.mark.parametrize(("path", "field"), [
    ("/v1/curves?L_mm=7_1", "L_mm"), ("/v1/curves?limit=1_0", "limit"),
    ("/v1/curves?limit=1.0", "limit"), ("/v1/predict/plot?nearby=2.0", "nearby"),
    ("/v1/predict/plot?L_mm=%D9%A7", "L_mm"),
    ("/v1/predict/plot?flow_ul_s=1_000", "flow_ul_s"),
    ("/v1/predict/plot?measured_pressure_pa=1_0&measured_angle_deg=1", "measured_pressure_pa")])
def test_a_query_reads_numbers_as_the_cli_does(shipped_client, path, field):
    """A query parameter in pydantic's lax mode read ``L_mm=7_1`` as 71 mm (refused as
    past 60 mm), ``flow_ul_s=1_000`` as 1000 ul/s (a plot) and ``limit=1.0`` as 1 (which
    ``-n 1.0`` refuses): the one rule, whole numbers for an integer field."""
    problem = assert_problem(shipped_client.get(path), 422, field)
    assert "ASCII decimal digits" in problem["errors"][0]["message"]


@pytest.mark.parametrize("cell", ["7_1", "٧", "７"])
def test_a_data_cell_reads_numbers_as_json_does(shipped_client, tmp_path, cell):
    """A measured-data cell written as text went through Python's float: over HTTP
    ``"L_mm": "7_1"`` was refused as "out of range: 71" and ``"٧"`` read as 7 mm; in a CSV
    file ``1_0`` was 10 mm. Refused naming the cell and the form."""
    rows = lab_rows()
    rows[2]["L_mm"] = cell
    problem = assert_problem(shipped_client.post("/v1/calibrate", json={
        "rows": rows, "model": "paper"}), 422, "rows.2.L_mm")
    assert "ASCII decimal digits" in problem["errors"][0]["message"], problem
    path = lab_csv(tmp_path, "2.5")
    text = path.read_text().splitlines()
    text[3] = text[3].replace(",7.1,", f",{cell},", 1)
    path.write_text("\n".join(text) + "\n")
    line = one_line_error(["calibrate", str(path), "--report", str(tmp_path / "r.json"),
                           "--model", "paper"])
    assert "L_mm: row 3" in line and "ASCII decimal digits" in line, line


def test_the_usual_forms_are_still_numbers(shipped_client):
    r = shipped_client.get("/v1/curves?L_mm=7.1&limit=2&t_mm=+.5")
    assert r.status_code == 200, r.text
    code, out, err, _ = run(["predict", "--L-mm", "+7.1", "--t-mm", ".5", "--pressures",
                             "1e3,1500", "--model", "paper"])
    assert code == 0, err


# -- 4. a listed design's time band past the longest pump time -------------------------------

def test_a_listed_designs_time_band_is_cut_at_the_longest_pump_time(shipped_client):
    """A time target of 99000 s at 3e-4 ul/s listed designs with ``time_upper_s``
    100611 s, past MAX_TIME_S (1e5 s), which /v1/predict's times_s refuses and the inverse
    by pressure withholds. Each edge past it is withheld, flagged, the volume kept."""
    r = shipped_client.post("/v1/inverse", json={
        "target": {"kind": "angle_at_time", "time_s": 99000, "flow_ul_s": 3e-4,
                   "angle_deg": 45}, "n_results": 3,
        "material_pairs": [{"body_material": "pdms_1_10",
                            "membrane_material": "ecoflex_00_30"}]})
    assert r.status_code == 200, r.text
    candidates = r.json()["candidates"]
    assert candidates
    for c in candidates:
        times = [c[n] for n in ("time_needed_s", "time_lower_s", "time_upper_s")]
        assert all(t is None or t <= MAX_TIME_S for t in times), times
        assert c["volume_upper_ul"] is not None
        if c["time_upper_s"] is None:
            assert "past_longest_pump_time" in c["validity"]["flags"]
            assert any(f"{MAX_TIME_S:g} s" in m for m in c["validity"]["messages"])
    assert any(c["time_upper_s"] is None for c in candidates)


# -- 5. unphysically soft materials ----------------------------------------------------------

def test_the_modulus_floor_lies_below_every_material_the_box_allows():
    softest = min(m.mu0_kpa for m in MATERIALS.values()) * STIFFNESS_SCALE_LIMITS[0]
    assert MIN_MU0_KPA < softest / 10
    make_material("softest", [m * STIFFNESS_SCALE_LIMITS[0] for m in
                              MATERIALS["ecoflex_00_30"].mu_kpa],
                  MATERIALS["ecoflex_00_30"].alpha)


SOFT = {"id": "soft", "mu_kpa": [1e-300], "alpha": [2.0]}


def test_an_fe_solve_of_an_unphysically_soft_material_is_refused_up_front(tmp_path):
    """``POST /v1/solve`` queued a membrane of mu 1e-300 kPa (mu0 > 0 was the only floor),
    which failed cleanly only after a 32 s solve. (A database of its own: the former code
    queued the job, and its record was written to the app's database.)"""
    from fastapi.testclient import TestClient
    from service_fakes import settings_for

    from service.app import create_app

    with TestClient(create_app(settings_for(tmp_path))) as client:
        r = client.post("/v1/solve", headers={"X-API-Key": "test-key"},
                        json={"design": {**DESIGN, "membrane_material": SOFT}})
        problem = assert_problem(r, 422, "design.membrane_material.mu_kpa")
        assert f">= {MIN_MU0_KPA:g} kPa" in problem["errors"][0]["allowed"]
        r = client.post("/v1/solve", headers={"X-API-Key": "test-key"},
                        json={"design": {**DESIGN, "body_material": "pdms_1_10*1e-5"}})
        problem = assert_problem(r, 422, "design.body_material")
        assert "scale >= " in problem["errors"][0]["allowed"]


def test_a_prediction_of_an_unphysically_soft_material_names_its_modulus(shipped_client):
    r = shipped_client.post("/v1/predict", json={
        "design": {**DESIGN, "membrane_material": SOFT}, "pressures_pa": [1000]})
    problem = assert_problem(r, 422, "design.membrane_material.mu_kpa")
    assert f">= {MIN_MU0_KPA:g} kPa" in problem["errors"][0]["allowed"]


def test_the_cli_solve_refuses_an_unphysically_soft_material():
    line = one_line_error(["solve", "--membrane-material", "ecoflex_00_30*1e-4"])
    assert "--membrane-material" in line and "mu0 >= 0.001 kPa" in line, line


# -- 6. the explorer's flow-rate box holding "1e999" -----------------------------------------

@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """The app with the shipped models, served for the browser test."""
    with LiveServer(tmp_path_factory.mktemp("explorer-s44")) as live:
        yield live


def shown_errors(page) -> dict[str, str]:
    return page.evaluate("""Object.fromEntries([...document.querySelectorAll('[id^=err-]')]
        .filter((e) => !e.hidden && e.textContent.trim()).map((e) => [e.id, e.textContent]))""")


@pytest.mark.timeout(300)
def test_a_flow_rate_too_large_for_a_double_is_out_of_range_and_kept(watched, server):
    """"1e999" typed in the time target's flow box: a number box reads it as "" (badInput),
    and the shared Curve panel's box was wiped with it; both said "not a number". The
    text stays in both boxes, each named out of range, and no search is sent."""
    page = open_explorer(watched, server.url)
    bodies: list = []
    page.on("request", lambda r: bodies.append(r.post_data_json)
            if r.url.endswith("/v1/inverse") and r.method == "POST" else None)
    page.select_option("#inv-kind", "angle_at_time")
    page.fill("#inv-time", "6")
    page.fill("#inv-angle", "40")
    page.click("#inv-flow")
    page.keyboard.press("Control+A")
    page.keyboard.type("1e999")
    page.keyboard.press("Tab")
    page.click("#inv-run")
    page.wait_for_selector("#err-inv-flow:not([hidden])")
    page.wait_for_selector("#err-flow_ul_s:not([hidden])")
    assert page.input_value("#inv-flow") == page.input_value("#flow") == "1e999"
    errors = shown_errors(page)
    for slot in ("err-inv-flow", "err-flow_ul_s"):
        assert "1e999 is outside the allowed range" in errors[slot], errors
        assert "from 0.000001 to 1000 ul/s" in errors[slot]
    assert bodies == []
    screenshot(page, "explorer-flow-1e999")
    # text that is no number in the service's form is named so (JavaScript reads 0x10 as 16)
    change(page, "#flow", "0x10")
    page.wait_for_function("document.getElementById('err-flow_ul_s').textContent"
                           ".includes('\"0x10\" is not a number')")
    # still stepped by the arrow keys, as a number box is
    change(page, "#flow", "2.5")
    page.focus("#flow")
    page.keyboard.press("ArrowUp")
    assert page.input_value("#flow") == page.input_value("#inv-flow") == "3.5"
    assert watched.foreign_requests() == [] and watched.errors == []


# -- 7. probed: a scaled preset's scale in other digits -------------------------------------

@pytest.mark.parametrize("scale", ["1_0", "１"])
def test_a_scaled_presets_scale_is_read_as_numbers_are(scale):
    """``--body-material 'pdms_1_10*1_0'`` was PDMS 1:10 ten times stiffer, and ``*１`` the
    preset (Python's float read the scale); HTTP's id pattern refuses both."""
    line = one_line_error(["predict", *CLI_DESIGN, "--pressures", "1000", "--body-material",
                           f"pdms_1_10*{scale}"])
    assert "--body-material: unknown material" in line, line


# -- 8. probed: very long names --------------------------------------------------------------

@pytest.mark.parametrize("argv", [
    ["predict", *CLI_DESIGN, "--pressures", "1000", "--model", "m" * 100_000],
    ["solve", "--body-material", "m" * 100_000],
    ["predict", *CLI_DESIGN, "--pressures", "1," + "x" * 5000]])
def test_the_cli_never_echoes_a_huge_word_whole(argv):
    """A model or material name of 100,000 characters was echoed whole: a 100 kB error
    line. A word past 100 characters is cut, its length said."""
    line = one_line_error(argv)
    assert len(line) < 600 and " characters)" in line, line[:300]


@pytest.mark.parametrize("body", [
    '{"design": {"L_mm": 7.1}, "pressures_pa": [1], "' + "k" * 50_000 + '": 1}',
    '{"design": {"L_mm": 7.1, "' + "k" * 20_000 + '": 1}, "pressures_pa": [1]}',
    '{"pressures_pa": [1], "' + "k" * 30_000 + '": 1, "' + "k" * 30_000 + '": 2}'])
def test_a_problem_never_echoes_a_huge_field_name_whole(shipped_client, body):
    """A field no schema has, named by 50,000 characters (or given twice), was echoed
    whole in the problem's detail, field and loc: 150 kB answering 50 kB."""
    r = shipped_client.post("/v1/predict", content=body,
                            headers={"content-type": "application/json"})
    problem = assert_problem(r, 422)
    assert len(r.content) < 2000 and " characters)" in problem["errors"][0]["field"]


def test_the_flow_rate_range_is_one_table_for_the_solver_and_the_pump():
    """The solver's settings took a flow rate up to 1e6 ul/s where every pump answer and
    measured data stop at 1000 (a second table, left alone by the round-five audit,
    closed in the forty-fourth session): both now read solver.settings' one table."""
    import surrogate.volume_control as volume_control
    from solver import settings
    from solver.settings import SolverSettings

    assert volume_control.MAX_FLOW_UL_S is settings.MAX_FLOW_UL_S == 1000.0
    assert volume_control.MIN_FLOW_UL_S is settings.MIN_FLOW_UL_S == 1e-6
    SolverSettings(flow_ul_s=1000.0).validated()
    for bad in (2000.0, 0.0):
        with pytest.raises(InputError) as exc:
            SolverSettings(flow_ul_s=bad).validated()
        assert exc.value.field == "flow_ul_s" and "1000" in exc.value.allowed
