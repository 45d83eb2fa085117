"""The forty-fifth session's hostile-input audit, round six (after tests/test_hostile_s44.py):
the CLI's lists held to HTTP's one limit, unstable Ogden materials refused up front (and
records of materials the input checks now refuse still readable), free-text labels with
control, bidi or zero-width characters, and the explorer's number boxes holding "1e999".

Each test failed on the code before its fix (commit messages say which).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from service_fakes import assert_problem
from test_cli_fuzz import run, visible_lines

from solver.errors import InputError
from surrogate.predictor import MAX_ASKED_VALUES

DESIGN = {"L_mm": 7.1, "t_mm": 0.5}
CLI_DESIGN = ["--L-mm", "7.1", "--t-mm", "0.5"]


def one_line_error(argv: list[str]) -> str:
    """The one stderr line of ``balloon argv`` refusing it (exit 2, nothing escaped)."""
    code, out, err, escaped = run(argv)
    lines = visible_lines(err)
    assert (code, escaped) == (2, None), (code, err[:300])
    assert len(lines) == 1 and lines[0].startswith("balloon"), err[:300]
    assert "Traceback" not in err
    return lines[0]


# -- 1. the most values one question asks: one table for the CLI and HTTP --------------------

@pytest.mark.parametrize(("argv", "option"), [
    (["predict", *CLI_DESIGN, "--model", "paper", "--pressures"], "--pressures"),
    (["predict", *CLI_DESIGN, "--volumes"], "--volumes"),
    (["predict", *CLI_DESIGN, "--flow-ul-s", "2.5", "--times"], "--times"),
    (["inverse", *CLI_DESIGN, "--angles-deg"], "--angles-deg")])
def test_the_cli_asks_at_most_as_many_values_as_http(argv, option):
    """``balloon predict --pressures`` took 100,000 numbers (6 s, a 16 MB --json) where
    ``POST /v1/predict`` refuses 1001: one limit, MAX_ASKED_VALUES, named with the option."""
    values = [str(1 + i % 50) for i in range(MAX_ASKED_VALUES + 1)]
    line = one_line_error([*argv, *values[:500], ",".join(values[500:])])
    assert option in line and f"{MAX_ASKED_VALUES + 1} values" in line, line
    assert f"1 to {MAX_ASKED_VALUES} values" in line, line


def test_the_cli_still_asks_the_limit_itself():
    code, out, err, escaped = run(["predict", *CLI_DESIGN, "--model", "paper", "--pressures",
                                   *[str(i) for i in range(MAX_ASKED_VALUES)]])
    assert (code, escaped) == (0, None), err


def test_the_schemas_lists_read_the_same_limit(shipped_client):
    schemas = shipped_client.get("/openapi.json").json()["components"]["schemas"]
    for schema, name in [("PredictRequest", "pressures_pa"), ("PredictRequest", "volumes_ul"),
                         ("PredictRequest", "times_s"), ("PressureRequest", "angles_deg")]:
        prop = schemas[schema]["properties"][name]
        lists = [p for p in prop.get("anyOf", [prop]) if p.get("type") == "array"]
        assert lists[0]["maxItems"] == MAX_ASKED_VALUES, (schema, name)


# -- 2. Ogden materials that nearly cancel: unstable ones refused up front --------------------

UNSTABLE = {"id": "nearly_cancel", "mu_kpa": [10.0, -5.0], "alpha": [2.0, 3.99]}


@pytest.mark.parametrize(("mu", "alpha"), [
    ([10.0, -5.0], [2.0, 3.99]),       # mu0 0.025 kPa, the stress falls from stretch 1
    ([1.0, 0.5], [2.0, -2.0]),         # mu0 0.5 kPa, equibiaxial stress falls at 1.19
    ([1.0, -0.02], [2.0, 8.0])])       # mu0 0.92 kPa, equibiaxial stress falls in compression
def test_an_unstable_material_is_refused_naming_its_moduli(mu, alpha):
    from solver.materials import make_material

    with pytest.raises(InputError) as exc:
        make_material("m", mu, alpha)
    assert exc.value.field == "mu_kpa"
    assert "unstable" in exc.value.detail and "stretch" in exc.value.detail
    assert "up to a stretch of 4" in exc.value.allowed


@pytest.mark.parametrize(("mu", "alpha"), [
    ([0.63, 0.0012, -0.01], [1.3, 5.0, -2.0]),   # Ogden's 1972 rubber: every mu*alpha > 0
    ([10.0, -9.99], [2.0, 2.0]),                 # a neo-Hookean of 0.01 kPa: soft, stable
    ([1.0, -0.5], [2.0, -2.0])])
def test_a_stable_material_is_taken(mu, alpha):
    from solver.materials import make_material

    make_material("m", mu, alpha)


def test_every_material_the_box_allows_is_stable():
    from solver.design_space import STIFFNESS_SCALE_LIMITS, scaled_material
    from solver.materials import MATERIALS
    from solver.ogden_paths import unstable_at

    for preset in MATERIALS:
        for scale in (*STIFFNESS_SCALE_LIMITS, 1.0):
            m = scaled_material(preset, scale)
            assert unstable_at(m.mu_kpa, m.alpha) is None, (preset, scale)


def test_the_path_stresses_are_the_energys_derivatives():
    """dW/dl and d2W/dl2 along each path against central differences of W_iso itself
    (solver.materials' form), at stretches in compression and tension."""
    from solver.ogden_paths import PATHS, path_stiffness_kpa, path_stress_kpa

    mu, alpha = [1.3, 0.2, -0.05], [2.5, 6.0, -3.0]

    def energy(lam, k):
        return sum(m / a * (lam ** a + lam ** (k * a) + lam ** (-(1 + k) * a) - 3)
                   for m, a in zip(mu, alpha))

    for k in PATHS.values():
        for lam in (0.5, 1.0, 2.7):
            h = 1e-4 * lam
            d1 = (energy(lam + h, k) - energy(lam - h, k)) / (2 * h)
            d2 = (energy(lam + h, k) - 2 * energy(lam, k) + energy(lam - h, k)) / h ** 2
            assert path_stress_kpa(mu, alpha, lam, k) == pytest.approx(d1, rel=1e-6, abs=1e-6)
            assert path_stiffness_kpa(mu, alpha, lam, k) == pytest.approx(d2, rel=1e-5)


def test_an_fe_solve_of_an_unstable_material_is_refused_up_front(tmp_path):
    """``POST /v1/solve`` queued a membrane of mu [10, -5] kPa, alpha [2, 3.99] (mu0
    0.025 kPa passes the floor), whose FE solve failed at rest after 21 s."""
    from fastapi.testclient import TestClient
    from service_fakes import settings_for

    from service.app import create_app

    with TestClient(create_app(settings_for(tmp_path))) as client:
        r = client.post("/v1/solve", headers={"X-API-Key": "test-key"},
                        json={"design": {**DESIGN, "membrane_material": UNSTABLE}})
        problem = assert_problem(r, 422, "design.membrane_material.mu_kpa")
        assert "unstable" in problem["detail"]


def test_a_grid_with_an_unstable_material_is_refused_naming_it(tmp_path):
    from solver.precompute.grid import GridError, load_grid

    grid = tmp_path / "grid.toml"
    grid.write_text('pairs = [["pdms_1_10", "bad"]]\nL_mm = 7.1\n\n'
                    '[materials.bad]\nmu_kpa = [10.0, -5.0]\nalpha = [2.0, 3.99]\n')
    with pytest.raises((GridError, InputError)) as exc:
        load_grid(grid)
    assert "unstable" in str(exc.value) and "mu_kpa" in str(exc.value)


def test_a_stored_material_the_checks_now_refuse_stays_readable(tmp_path):
    """A record stored before the mu0 floor (tests/test_hostile_s44.py: the app's own
    database took a membrane of mu 1e-300 kPa) read back through the input checks: "record
    ... is damaged", ``db export`` refused the whole file and a precompute would refuse
    to write to it. A stored material is read as written."""
    from test_precompute_fakes import fake_curve

    from solver.design import Design
    from solver.materials import OgdenMaterial
    from solver.settings import SolverSettings
    from solver.store import CurveStore, make_record

    path = tmp_path / "old.h5"
    settings = SolverSettings(mesh_level=0, element="hex1")
    stored = [OgdenMaterial("soft", (1e-300,), (2.0,)),
              OgdenMaterial("nearly_cancel", (10.0, -5.0), (2.0, 3.99))]
    with CurveStore(path, mode="a") as db:
        for material in stored:
            design = Design(L_mm=7.1, t_mm=0.5, membrane_material=material)
            db.put(make_record(design, settings, fake_curve(design, status="failed",
                                                           reason="fake")))
    with CurveStore(path) as db:
        got = [db.get(key).design.membrane_material for key in db.keys()]
    assert sorted(got, key=lambda m: m.id) == sorted(stored, key=lambda m: m.id)
    code, out, err, escaped = run(["db", "export", str(path), "-o", str(tmp_path / "o.csv")])
    assert (code, escaped) == (0, None), err


# -- 3. free-text labels with control, bidi-override or zero-width characters -----------------

EXAMPLE = Path(__file__).resolve().parents[1] / "surrogate/calibration/data/example_lab.csv"
FIRST_CURVE = "L7.1-t0.75-q1.25-s1"
# an ANSI colour and a screen clear (ESC [ 2 J), a bidi override, a zero-width space, the
# C1 control CSI (U+009B), a bell
HOSTILE = ["\x1b[31mred\x1b[0m", "ok\x1b[2J", "s1\u202e2s", "s\u200b1", "s\x9b2J", "s\x07"]
RAW = ("\x1b", "\u202e", "\u200b", "\x9b", "\x07")


def lab_rows(curve_id: str = "s1") -> list[dict]:
    return [{"curve_id": c, **DESIGN, "body_material": "pdms_1_10",
             "membrane_material": "ecoflex_00_30", "pressure_pa": p, "angle_deg": a}
            for c in (curve_id, "s2")
            for p, a in ((0, 0.1), (400, 1.6), (800, 4.8), (1200, 12.0))]


@pytest.mark.parametrize("label", HOSTILE)
def test_a_curve_id_that_a_terminal_would_obey_is_refused_on_the_cli(tmp_path, label):
    """``balloon calibrate`` took a curve_id holding ESC [ 31 m, U+202E or U+200B, and
    its report (--report) and the HTTP answer carried it raw into every reader's terminal
    or page. Refused naming the column, the row and the character, shown escaped."""
    path = tmp_path / "lab.csv"
    path.write_text(EXAMPLE.read_text().replace(FIRST_CURVE, label))
    report = tmp_path / "r.json"
    line = one_line_error(["calibrate", str(path), "--report", str(report), "--model",
                           "paper"])
    assert "curve_id: row 1: a control or invisible character U+" in line, line
    assert "printable text" in line
    assert not any(c in line for c in RAW), ascii(line)
    assert not report.exists()


@pytest.mark.parametrize("label", HOSTILE)
def test_a_curve_id_that_a_page_would_obey_is_refused_over_http(shipped_client, label):
    r = shipped_client.post("/v1/calibrate", json={"rows": lab_rows(label), "model": "paper"})
    problem = assert_problem(r, 422, "rows.0.curve_id")
    assert "U+" in problem["detail"] and not any(c in r.text for c in RAW), ascii(r.text)


def test_a_run_label_is_held_to_the_same_rule(shipped_client):
    rows = [{**row, "run": "1\u200b"} for row in lab_rows()]
    problem = assert_problem(shipped_client.post("/v1/calibrate", json={
        "rows": rows, "model": "paper"}), 422, "rows.0.run")
    assert "U+200B (ZERO WIDTH SPACE)" in problem["detail"]


@pytest.mark.parametrize("key", ["x\u202eevil", "k\x9b2J", "zero\u200bwidth", "b\x07ell"])
def test_a_problem_never_carries_a_made_up_names_hidden_characters(shipped_client, key):
    """A column (or field) name the request made up was echoed in the problem's detail,
    loc and field as sent: JSON escapes only U+0000-U+001F, so a bidi override, a zero-width
    space and the C1 CSI reached the reader raw. Every text of a problem is shown escaped."""
    rows = lab_rows()
    rows[0][key] = 1
    r = shipped_client.post("/v1/calibrate", json={"rows": rows, "model": "paper"})
    problem = assert_problem(r, 422)
    assert not any(c in r.content.decode() for c in RAW), ascii(r.text)
    assert "unknown column" in problem["detail"]
    r = shipped_client.post("/v1/predict", json={"design": {**DESIGN, key: 1},
                                                 "pressures_pa": [1000]})
    assert_problem(r, 422)
    assert not any(c in r.content.decode() for c in RAW), ascii(r.text)


# -- 3 and 4 in the explorer: a hostile name shown escaped, "1e999" in every number box ------

@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """The app with the shipped models, served for the browser tests."""
    from explorer_browser import LiveServer

    with LiveServer(tmp_path_factory.mktemp("explorer-s45")) as live:
        yield live


@pytest.mark.timeout(300)
def test_the_page_shows_a_hostile_column_name_escaped(watched, server, tmp_path):
    """A CSV whose extra column is named with a bidi override and a zero-width space: the
    server's problem echoed the name raw and the page showed it so (text after U+202E is
    drawn right to left); now escaped. A curve_id holding U+202E is refused, named."""
    from explorer_browser import open_explorer, screenshot

    page = open_explorer(watched, server.url)
    lines = [x for x in EXAMPLE.read_text().splitlines() if x.strip() and not x.startswith("#")]

    def refusal(name: str, rows: list[str], words: str) -> str:
        path = tmp_path / name
        path.write_text("\n".join(rows) + "\n")
        page.set_input_files("#cal-file", str(path))
        page.click("#cal-run")
        page.wait_for_function("document.getElementById('err-cal-rows').textContent"
                               f".includes('{words}')")
        text = page.locator("#err-cal-rows").inner_text()
        assert not any(c in text for c in RAW), ascii(text)
        return text

    text = refusal("hostile-header.csv", [lines[0] + ",note\u202etxt.exe\u200b"]
                   + [x + ",1" for x in lines[1:21]], "unknown column")
    assert "\\u202e" in text
    screenshot(page, "explorer-hostile-column-name")
    text = refusal("hostile-id.csv", [lines[0]] + [x.replace(FIRST_CURVE, "s1\u202e2s")
                                                   for x in lines[1:40]], "U+202E")
    assert "curve_id" in text
    assert all("status of 422" in e for e in watched.errors), watched.errors


def shown_error(page, slot: str) -> str:
    page.wait_for_selector(f"{slot}:not([hidden])")
    return page.inner_text(slot)


@pytest.mark.timeout(300)
def test_every_number_box_names_1e999_out_of_range_with_its_range(watched, server):
    """Every number box but the flow rate's read "1e999" as "" (badInput): a design field
    said "not a number", the grid's largest pressure "not a number", the search's target
    was sent as "not a number" and refused by the server as "Input should be a valid
    number", the calibration's folds were read as 5. Every box is now a text box read by
    fields.js' one reading: out of range, with its range, the text kept, nothing sent."""
    from explorer_browser import change, open_explorer, screenshot

    page = open_explorer(watched, server.url)
    searches: list = []
    page.on("request", lambda r: searches.append(r.url)
            if r.url.endswith(("/v1/inverse", "/v1/calibrate")) and r.method == "POST" else None)
    change(page, "#L_mm", "1e999")
    assert shown_error(page, "#err-L_mm") == ("Chamber length L (mm): 1e999 is outside the "
                                              "allowed range (allowed: 4 to 18 mm)")
    assert page.input_value("#L_mm") == "1e999"
    change(page, "#L_mm", "7.1")
    change(page, "#p_max", "1e999")
    error = shown_error(page, "#err-pressures_pa")
    assert "1e999 is outside the allowed range (allowed: from 100 to 20000 Pa)" in error, error
    change(page, "#p_max", "2000")
    change(page, "#nearby", "-1e999")
    assert "-1e999 is outside the allowed range (allowed: a whole number from 0 to 6" in \
        shown_error(page, "#err-nearby")
    change(page, "#nearby", "3")
    # the design search: each box's text checked on the page, nothing sent
    page.select_option("#inv-kind", "angle_at_volume")
    page.fill("#inv-volume", "1e999")
    page.fill("#inv-angle", "1e400")
    page.click("#inv-run")
    assert "1e999 is outside the allowed range (allowed: to 500 ul)" in \
        shown_error(page, "#err-inv-volume")
    assert "1e400 is outside the allowed range (allowed: from -360 to 360 deg)" in \
        shown_error(page, "#err-inv-angle")
    screenshot(page, "explorer-number-boxes-1e999")
    # the calibration's folds
    page.set_input_files("#cal-file", str(EXAMPLE))
    page.fill("#cal-folds", "abc")
    page.click("#cal-run")
    assert '"abc" is not a number (allowed: a whole number from 2 to 50)' in \
        shown_error(page, "#err-cal-folds")
    assert searches == []
    # still stepped by the arrow keys by the box's step, as a number box was
    change(page, "#L_mm", "7.1")
    page.focus("#L_mm")
    page.keyboard.press("ArrowUp")
    assert page.input_value("#L_mm") == "7.2"
    page.focus("#p_max")
    page.keyboard.press("ArrowDown")
    assert page.input_value("#p_max") == "1900"
    assert watched.foreign_requests() == [] and watched.errors == []


# -- 5. probed: a negative number in exponent form on the command line -----------------------

REVERSED = ["--L-mm", "11.1", "--t-mm", "0.5", "--body-material", "ecoflex_00_30",
            "--membrane-material", "pdms_1_15"]


def test_a_negative_angle_in_exponent_form_is_a_value():
    """argparse reads -5 and -2.5 as values but -1.5e1 as an unknown option: a reversed
    pair's ``--angles-deg -1.5e1`` said "expected at least one argument" (-15 answered)."""
    code, out, err, escaped = run(["inverse", *REVERSED, "--angles-deg", "-1.5e1", "-2E1"])
    assert (code, escaped) == (0, None), err
    assert "-15.00" in out and "-20.00" in out


@pytest.mark.parametrize(("argv", "words"), [
    (["predict", "--L-mm", "-1e3", "--t-mm", "0.5", "--pressures", "1000"],
     "--L-mm: got -1000.0 (allowed: 0.5 <= L_mm <= 60.0)"),
    (["predict", *CLI_DESIGN, "--pressures", "1000", "-1e3"],
     "--pressures: -1000 Pa is out of range (allowed: 0..20000 Pa)")])
def test_a_negative_number_in_exponent_form_is_named_with_its_range(argv, words):
    """``--L-mm -1e3`` said "argument --L-mm: expected one argument" and ``--pressures
    1000 -1e3`` "unrecognized arguments: -1e3": neither the option's range."""
    assert words in one_line_error(argv)
