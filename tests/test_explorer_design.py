"""The explorer's design tasks in real headless Chromium: inverse design lists ranked
candidates and loading one updates the design panel; the shipped example CSV gives the
calibration report, and saving the augmented model (with the key) overlays it; a design the
predictor refuses offers the FE solve, which queues a job (fake solve in a real worker
process, stored in a copy of the database), shows its progress and plots the stored curve.
Screenshots: test-artifacts/explorer/."""

from __future__ import annotations

import csv
import json
import re

import httpx
import pytest
from explorer_browser import (
    API_KEY,
    ROOT,
    LiveServer,
    open_explorer,
    screenshot,
)
from service_solves import fast_solve

EXAMPLE_CSV = ROOT / "surrogate" / "calibration" / "data" / "example_lab.csv"


pytestmark = pytest.mark.timeout(300)  # a browser that hangs fails the test

@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with LiveServer(tmp_path_factory.mktemp("explorer-design"), solve_fn=fast_solve) as live:
        yield live




def test_inverse_design_lists_candidates_and_loading_one_updates_the_panel(watched, server):
    page = open_explorer(watched, server.url)
    page.fill("#inv-pressure", "1500")
    page.fill("#inv-angle", "45")
    page.fill("#inv-n", "3")
    page.click("#inv-run")
    # the search covers the whole design box: seconds, more on a loaded machine
    page.wait_for_selector("#inv-table tbody tr", timeout=180_000)
    body = {"target": {"kind": "angle_at_pressure", "pressure_pa": 1500, "angle_deg": 45},
            "n_results": 3}
    api = httpx.post(server.url + "/v1/inverse", json=body, timeout=180).json()
    rows = page.locator("#inv-table tbody tr")
    assert rows.count() == len(api["candidates"]) == 3
    assert api["explanation"] in page.locator("#inv-explanation").inner_text()
    second = api["candidates"][1]
    row = rows.nth(1).inner_text()
    for key, digits in (("L_mm", 2), ("t_mm", 3), ("T_mm", 3), ("b_mm", 3), ("h_mm", 3)):
        assert f"{second[key]:.{digits}f}" in row, key
    page.locator('#inv-table button[data-candidate="1"]').click()
    page.wait_for_function(f"window.explorer.prediction && Math.abs(window.explorer.prediction"
                           f".design.L_mm - {second['L_mm']}) < 1e-3")
    assert float(page.input_value("#L_mm")) == pytest.approx(second["L_mm"], abs=1e-4)
    for key in ("t_mm", "T_mm", "b_mm", "h_mm"):
        assert float(page.input_value(f"#{key}")) == pytest.approx(second[key], abs=1e-4), key
    state = page.evaluate("window.explorer.request.design")  # what the page sent
    assert state["W_mm"] == pytest.approx(second["design"]["W_mm"])
    for key in ("T_mm", "b_mm", "h_mm"):
        assert state[key] == pytest.approx(second[key], abs=1e-4), key
    for layer in ("body", "membrane"):  # a scale != 1 is sent as an inline scaled material
        scale = second[f"{layer}_stiffness_scale"]
        assert float(page.input_value(f"#{layer}_scale")) == pytest.approx(scale, abs=0.05)
        sent = state[f"{layer}_material"]
        sent_id = sent if isinstance(sent, str) else sent["id"]
        assert sent_id.startswith(second[f"{layer}_material"])
    names = {"pdms_1_10": "PDMS 1:10", "pdms_1_15": "PDMS 1:15", "ecoflex_00_30": "Ecoflex 00-30"}
    pair = page.locator("#pair option:checked").inner_text()
    assert pair == f"{names[second['body_material']]} / {names[second['membrane_material']]}"
    # at the target pressure the panel shows /v1/predict's angle for the design it sent
    at_target = httpx.post(server.url + "/v1/predict", json={
        "design": page.evaluate("window.explorer.request.design"), "pressures_pa": [1500]}).json()
    shown = page.locator("#p_op-out").inner_text()
    assert f"1500 Pa: angle {at_target['angle_deg'][0]:.1f} deg" in shown
    screenshot(page, "explorer-inverse-1280")
    assert watched.errors == []


def test_an_unreachable_target_is_explained_and_a_bad_bound_shown_beside_its_field(watched, server):
    page = open_explorer(watched, server.url)
    page.fill("#inv-angle", "300")
    page.fill("#inv-pressure", "200")
    page.click("#inv-run")
    page.wait_for_function("document.getElementById('inv-explanation').textContent.length > 20")
    assert page.locator("#inv-table").is_hidden()
    page.fill("#inv-L-lo", "70")
    page.fill("#inv-L-hi", "80")
    page.click("#inv-run")
    page.wait_for_selector("#err-inv-L:not([hidden])")
    assert "60" in page.locator("#err-inv-L").inner_text()  # the allowed range is named
    assert page.get_attribute("#inv-L-lo", "aria-invalid") == "true"


def test_a_german_excel_csv_is_read_as_the_comma_separated_file(watched, server):
    """A German Excel's CSV (a byte-order mark, ';' between fields, ',' as the decimal
    mark, rows of separators only at the end) was refused before sending ("save the file
    as comma-separated values", which such an Excel cannot do); the page now sends the
    rows the comma-separated file gives, as the CLI reads them."""
    plain = EXAMPLE_CSV.read_text()
    lines = [ln.split(",") for ln in plain.splitlines() if not ln.startswith("#")]
    german = "\ufeff# lab 2\r\n" + "".join(
        ";".join(cell if k in (0, 3, 4) else cell.replace(".", ",")
                 for k, cell in enumerate(cells)) + "\r\n"
        for cells in lines) + ";;;;;;;;\r\n\r\n"
    page = open_explorer(watched, server.url)
    read = page.evaluate("""async ([a, b]) => {
        const m = await import("/static/explorer/js/csv.js");
        return [m.parseCsv(a), m.parseCsv(b)];
    }""", [german, plain])
    assert read[0] == read[1] and len(read[0]) == 288


def test_the_reports_own_fit_is_drawn_beside_the_data_before_any_save(watched, server):
    """The report carries its fit at each reading (``predictions``): the page draws it at
    once. Before, it said the fitted curves would be drawn "once it is saved" while Save
    was greyed out, and named the emulator's cross-validated error "recalibrated
    constants" (an audit of the thirty-fifth session)."""
    page = open_explorer(watched, server.url)
    page.set_input_files("#cal-file", str(EXAMPLE_CSV))
    page.click("#cal-run")
    page.wait_for_selector("#cal-report:not([hidden])", timeout=120_000)
    page.wait_for_selector('#cal-plot g[data-series="fit-report"] circle', timeout=60_000)
    fit = page.locator('#cal-plot g[data-series="fit-report"] circle')
    assert fit.count() > 20
    assert "once it is saved" not in page.locator("#cal-status").inner_text()
    assert "nothing to recalibrate" in page.locator("#cal-errors").inner_text()


def test_uploading_the_example_csv_shows_the_report_and_saving_asks_for_the_key(watched, server):
    page = open_explorer(watched, server.url)
    page.set_input_files("#cal-file", str(EXAMPLE_CSV))
    page.fill("#cal-model", "paper")
    page.click("#cal-run")
    page.wait_for_selector("#cal-report:not([hidden])", timeout=60_000)
    with open(EXAMPLE_CSV) as f:  # docs/measured-data.md: '#' lines are comments
        lines = [line for line in f if line.strip() and not line.lstrip().startswith("#")]
    rows = [{k: (v if k in ("curve_id", "body_material", "membrane_material") else float(v))
             for k, v in r.items() if v != ""} for r in csv.DictReader(lines)]
    designs = {(r["L_mm"], r["t_mm"], r["body_material"], r["membrane_material"]) for r in rows}
    api = httpx.post(server.url + "/v1/calibrate", json={"rows": rows, "model": "paper"},
                     timeout=60).json()
    assert page.locator("#cal-interpretation").inner_text() == api["interpretation"]
    errors = page.locator("#cal-errors").inner_text()
    assert f"{api['rmse_model_deg']:.2f}" in errors and f"{api['rmse_after_deg']:.2f}" in errors
    effects = page.locator("#cal-effects").inner_text()
    for effect in api["selected_effects"]:
        assert effect.replace("_", " ") in effects
    assert page.locator("#cal-candidates tbody tr").count() == len(api["candidates"])
    # data and the model as is are drawn; the residuals of the model as is too
    # one colour per design
    assert page.locator('#cal-plot g[data-series^="data-"]').count() == len(designs)
    assert page.locator('#cal-plot g[data-series^="before-"]').count() == len(designs)
    # a residual for each row at a pressure the model takes (a reading below 0 Pa has none)
    at_model = [r for r in rows if r["pressure_pa"] >= 0]
    assert page.locator('#cal-resid g[data-series^="rb-"] circle').count() == len(at_model)
    with page.expect_download() as d:
        page.click("#cal-download")
    assert json.loads(open(d.value.path()).read())["interpretation"] == api["interpretation"]
    screenshot(page, "explorer-calibration-1280")

    page.fill("#save-name", "lab_example")
    page.click("#save-run")  # no key: asked for, nothing sent
    page.wait_for_selector("#err-save-key:not([hidden])")
    page.fill("#save-key", "wrong")
    page.click("#save-run")
    page.wait_for_function("document.getElementById('err-save-key').textContent.length > 0")
    assert not (server.settings.models_dir / "lab_example.json").exists()
    page.fill("#save-key", API_KEY)
    page.click("#save-run")
    page.wait_for_selector('#cal-plot g[data-series^="after-"]', timeout=60_000)
    assert "lab_example" in page.locator("#cal-status").inner_text()
    assert (server.settings.models_dir / "lab_example.json").exists()
    assert page.locator('#cal-resid g[data-series^="ra-"] circle').count() == len(at_model)
    page.locator("#cal-plot").scroll_into_view_if_needed()
    screenshot(page, "explorer-calibration-saved-1280")


def test_the_report_names_the_explanations_the_data_cannot_tell_apart(watched, server):
    # a report in the shape surrogate/calibration/_loop.py writes (docs/calibration.md)
    report = {"selected_effects": ["body_stiffness"],
              "indistinguishable": [{"effects": ["pressure_offset"], "rmse_cv_deg": 1.234,
                                     "paired_z": -0.8, "backed": True,
                                     "params": {"p0_pa": {"value": 118.0, "sd": 9.0,
                                                          "unit": "Pa"}},
                                     "measure": ["read the gauge at rest"]}],
              "closest_rejected": {"effects": ["angle_offset"], "rmse_cv_deg": 2.5,
                                   "why_not": ["rule 3: not backed"],
                                   "params": {"offset_deg": {"value": 1.5, "sd": 0.4,
                                                             "unit": "deg"}}}}
    page = open_explorer(watched, server.url)
    lines = page.evaluate("async (r) => (await import('/static/explorer/js/calibration.js'))"
                          ".alternativeLines(r)", report)
    text = " | ".join(line["text"] for line in lines)
    assert "pressure offset" in text and "p0_pa = 118 +/- 9.0 Pa" in text
    assert "read the gauge at rest" in text and "1.23" in text
    assert "angle offset" in text and "rule 3: not backed" in text
    assert page.evaluate("async () => (await import('/static/explorer/js/calibration.js'))"
                         ".alternativeLines({}).length") == 0
    # the same readings exactly (_exact_alike.py): said so, not as "equally consistent"
    exact = {"effects": ["membrane_stiffness", "body_stiffness"], "rmse_cv_deg": 0.8,
             "paired_z": 0.0, "backed": True, "exact": True, "why": "both layers' mu x k",
             "params": {"body_mu_scale": {"value": 0.936, "sd": 0.012, "unit": "-"}},
             "measure": ["check the gauge against a reference gauge at two pressures"]}
    lines = page.evaluate("async (r) => (await import('/static/explorer/js/calibration.js'))"
                          ".alternativeLines(r)", {"indistinguishable": [exact]})
    assert lines[0]["text"].startswith("The same readings exactly: membrane stiffness")
    assert "both layers' mu x k" in lines[0]["text"] and "reference gauge" in lines[0]["text"]


def test_a_refused_design_offers_the_fe_solve_and_plots_the_stored_curve(watched, server):
    page = open_explorer(watched, server.url)
    assert page.locator("#refused").is_hidden()
    page.fill("#L_mm", "3")  # outside the emulator's box (L 4..18 mm), inside DesignIn's
    page.wait_for_selector("#refused:not([hidden])")
    refusal = httpx.post(server.url + "/v1/predict", json={
        "design": {"L_mm": 3}, "pressures_pa": [0, 1000]}).json()
    assert refusal["status"] == 422
    # the refusal names the field, the nearest design inside the box and the FE solve;
    # it is said once, in the FE solve box beside the plot
    assert refusal["errors"][0]["field"] in ("L_mm", "design.L_mm")
    assert "nearest design" in refusal["detail"] and "/v1/solve" in refusal["detail"]
    detail = page.locator("#refused-detail").inner_text()
    assert refusal["errors"][0]["message"][:60] in detail
    assert "nearest design" in detail and "/v1/solve" in detail
    assert page.locator("#err-design").is_hidden()
    assert page.locator("#err-L_mm").is_hidden()
    screenshot(page, "explorer-refused-1280")
    page.fill("#api_key", "")
    page.click("#solve")  # no key: asked for beside the key field
    page.wait_for_selector("#err-api_key:not([hidden])")
    page.fill("#api_key", API_KEY)
    page.click("#solve")
    page.wait_for_function("document.getElementById('job').dataset.status === 'finished'",
                           timeout=60_000)
    page.wait_for_selector('#plot g[data-series="fe-solve"]')
    # the stored curve replaces the solve's progress dots (tests/test_explorer_audit_s49.py)
    assert page.locator('#plot g[data-series="fe-progress"]').count() == 0
    drawn = json.loads(page.locator('#plot g[data-series="fe-solve"]').get_attribute("data-y"))
    curve_id = page.get_attribute("#job", "data-curve-id")
    assert curve_id in page.locator("#job").inner_text()
    stored = httpx.get(f"{server.url}/v1/curves/{curve_id}").json()
    assert stored["design"]["L_mm"] == 3
    assert drawn == pytest.approx(stored["curve"]["angle_deg"])
    # solving it again finds it in the database (409 with the curve id): it is loaded
    page.click("#solve")
    page.wait_for_function("document.getElementById('job').textContent.includes('Already')")
    screenshot(page, "explorer-fe-solve-1280")
    console = [e for e in watched.errors if "status of 4" not in e]  # the refusals themselves
    assert console == [], console


def test_a_force_target_no_design_reaches_is_said_beside_the_target(watched, server):
    # 10 mN at 1500 Pa: the emulator's blocked-tip forces in the box stay below 1 mN, so
    # the box-wide search answers "not reachable" with the largest force it found (a
    # model without force would answer a problem on the target's kind instead)
    answer = httpx.post(server.url + "/v1/inverse", json={
        "target": {"kind": "force_at_pressure", "pressure_pa": 1500, "force_mn": 10}},
        timeout=120)
    page = open_explorer(watched, server.url)
    page.select_option("#inv-kind", "force_at_pressure")
    assert page.locator("#inv-force").is_visible() and page.locator("#inv-angle").is_hidden()
    page.fill("#inv-force", "10")
    page.click("#inv-run")
    if answer.status_code == 200:
        body = answer.json()
        assert body["feasible"] is False and "not reachable" in body["explanation"]
        page.wait_for_function("document.getElementById('inv-explanation').textContent"
                               ".includes('not reachable')", timeout=120_000)
        assert body["explanation"] in page.locator("#inv-explanation").inner_text()
    else:
        page.wait_for_selector("#err-inv-kind:not([hidden])")
        assert (answer.json()["errors"][0]["message"]
                in page.locator("#err-inv-kind").inner_text())


def test_a_reachable_force_target_lists_forces_to_three_significant_digits(watched, server):
    # forces at these sizes are fractions of a mN: to 0.1 mN every row read "0.2 [0.2, 0.2]"
    # (an audit of the thirty-fifth session); the form's default is a reachable 0.5 mN
    page = open_explorer(watched, server.url)
    page.select_option("#inv-kind", "force_at_pressure")
    assert float(page.input_value("#inv-force")) < 1.0
    page.fill("#inv-force", "0.3")
    page.click("#inv-run")
    page.wait_for_function("!document.getElementById('inv-table').hidden", timeout=120_000)
    header = [h.inner_text() for h in page.locator("#inv-table thead th").all()]
    column = next(i for i, h in enumerate(header) if "force" in h)
    cells = [row.locator("td").nth(column).inner_text()
             for row in page.locator("#inv-table tbody tr").all()]
    assert cells
    for cell in cells:
        value, band = cell.split(" ", 1)
        assert re.fullmatch(r"0\.\d{3}", value), cell       # 0.300, not 0.3
        low, high = (float(v) for v in re.findall(r"[\d.]+", band))
        assert low < float(value) < high, cell


def test_an_inline_stiffness_scaled_material_is_sent_with_scaled_moduli(watched, server):
    page = open_explorer(watched, server.url)
    sent = []
    page.on("request", lambda r: (sent.append(r.post_data_json)
                                  if r.url.endswith("/v1/predict") else None))
    page.fill("#membrane_scale", "1.5")
    page.wait_for_function("window.explorer.request && typeof window.explorer.request.design"
                           ".membrane_material === 'object'")
    materials = {m["id"]: m for m in httpx.get(server.url + "/v1/materials").json()["items"]}
    membrane = sent[-1]["design"]["membrane_material"]
    assert membrane["id"] == "ecoflex_00_30_x1.5"
    preset = materials["ecoflex_00_30"]
    assert membrane["mu_kpa"] == pytest.approx([1.5 * m for m in preset["mu_kpa"]])
    assert membrane["alpha"] == materials["ecoflex_00_30"]["alpha"]
    assert sent[-1]["design"]["body_material"] == "pdms_1_10"
