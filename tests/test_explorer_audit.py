"""The explorer's fixes from the lab-user audit (findings numbered as in the audit), in real
headless Chromium on one live server: a scaled copy keeps full precision; the page names an
empty or out-of-range field beside it and never sends another value; one message for a
grid over the server's limit; legible plot text at 400 px; a pasted link applies; an
inverse design's target pressure is shown; a stopped service is said plainly and the page
recovers; an FE solve that ends early says where and why and is shown again after a
reload; calibration errors name their column and a failed upload hides the old report.
Slow server work (inverse search, calibration) is answered by route interception where
only the page's handling is under test. Screenshots: test-artifacts/explorer/audit-*.png.
"""

from __future__ import annotations

import json

import pytest
from explorer_browser import (
    API_KEY,
    ROOT,
    LiveServer,
    Watched,
    change,
    open_explorer,
    screenshot,
    wait_prediction,
)
from service_solves import make_curve

pytestmark = pytest.mark.timeout(300)

EXAMPLE_CSV = ROOT / "surrogate" / "calibration" / "data" / "example_lab.csv"
REASON = "step at p = 3000 Pa did not converge"


def partial_solve(design, settings, on_step=None):
    """A solve that ends early: four steps to 30 deg at 3000 Pa, then no convergence."""
    for step in range(1, 4):
        if on_step:
            on_step({"step": step, "pressure_pa": 1000.0 * step, "volume_ul": 1.0 * step,
                     "angle_deg": 10.0 * step, "newton_iterations": 4})
    return make_curve(4, status="failed", reason=REASON)


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with LiveServer(tmp_path_factory.mktemp("explorer-audit"), solve_fn=partial_solve) as live:
        yield live


def predict_posts(watched) -> int:
    return sum(1 for u in watched.requests if u.endswith("/v1/predict"))


def series_ids(page) -> list[str]:
    return page.eval_on_selector_all("#plot g[data-series]", "gs => gs.map(g => g.dataset.series)")


# ------------------------------------------------------------------ 1: width W
def test_1_a_new_width_keeps_the_scaled_copy_in_the_box(watched, server):
    page = open_explorer(watched, server.url)
    page.fill("#W_mm", "3.2")
    wait_prediction(page, W_mm=3.2)
    assert page.locator("#refused").is_hidden()
    assert page.input_value("#t_mm") == "0.5333"  # shown rounded
    assert page.evaluate("window.explorer.state.t_mm") == pytest.approx(0.5 * 3.2 / 3, abs=1e-12)
    page.fill("#W_mm", "9.2")
    wait_prediction(page, W_mm=9.2)
    page.fill("#W_mm", "2.6")
    wait_prediction(page, W_mm=2.6)
    assert page.locator("#refused").is_hidden()
    assert page.evaluate("window.explorer.state.t_mm") == pytest.approx(0.5 * 2.6 / 3, abs=1e-12)
    assert watched.errors == []


# ------------------------------------------------------------------ 5, 6, 19: fields
def test_5_19_an_empty_or_out_of_range_field_is_named_beside_it_and_nothing_else_is_sent(
        watched, server):
    page = open_explorer(watched, server.url)
    before = predict_posts(watched)
    link = page.evaluate("location.hash")
    change(page, "#p_max", "-100")
    page.wait_for_selector("#err-pressures_pa:not([hidden])")
    text = page.locator("#err-pressures_pa").inner_text()
    assert "Largest pressure" in text and "100" in text and "20000" in text, text
    assert page.evaluate("window.explorer.prediction") is None
    assert "Largest pressure" in page.locator("#status").inner_text()
    # tied to its input for a screen reader
    assert page.get_attribute("#p_max", "aria-invalid") == "true"
    assert "err-pressures_pa" in page.get_attribute("#p_max", "aria-describedby")
    assert page.get_attribute("#err-pressures_pa", "role") == "alert"
    page.wait_for_timeout(300)
    assert predict_posts(watched) == before  # 2000 Pa is not asked in its place
    assert page.evaluate("location.hash") == link
    screenshot(page, "audit-pmax-negative-1280")
    change(page, "#p_max", "2000")
    page.wait_for_selector("#err-pressures_pa", state="hidden")
    page.wait_for_function("window.explorer.prediction !== null")
    assert "err-pressures_pa" not in (page.get_attribute("#p_max", "aria-describedby") or "")
    # an emptied design field is not silently kept at its former value
    page.fill("#t_mm", "")
    page.wait_for_selector("#err-t_mm:not([hidden])")
    assert "Membrane thickness t" in page.locator("#err-t_mm").inner_text()
    assert "0.5" in page.locator("#err-t_mm").inner_text()
    assert page.evaluate("window.explorer.prediction") is None
    page.fill("#t_mm", "0.6")
    wait_prediction(page, t_mm=0.6)
    page.fill("#W_mm", "0")
    page.wait_for_selector("#err-W_mm:not([hidden])")
    assert "Actuator width W" in page.locator("#err-W_mm").inner_text()
    assert page.evaluate("window.explorer.prediction") is None
    page.fill("#W_mm", "3")
    wait_prediction(page, W_mm=3, t_mm=0.6)
    # the nearest-curves count: said, and no curves drawn rather than 6 of them
    change(page, "#nearby", "50")
    page.wait_for_selector("#err-nearby:not([hidden])")
    assert "0" in page.locator("#err-nearby").inner_text()
    assert "6" in page.locator("#err-nearby").inner_text()
    page.wait_for_function("!document.querySelector('#plot g[data-series^=\"fe-\"]')")


def test_6_a_grid_over_the_servers_limit_is_one_message_naming_the_field(watched, server):
    page = open_explorer(watched, server.url)
    change(page, "#p_max", "50000")  # the page's own check, from the input's limit
    page.wait_for_selector("#err-pressures_pa:not([hidden])")
    assert page.locator("#err-pressures_pa").inner_text().count("20000") == 1
    # without the page's check the server names every grid point over 20000 Pa: said once
    page.evaluate("document.getElementById('p_max').removeAttribute('max')")
    change(page, "#p_max", "50001")
    page.wait_for_function("document.getElementById('err-pressures_pa').textContent"
                           ".includes('less than or equal')")
    text = page.locator("#err-pressures_pa").inner_text()
    assert text.count("less than or equal") == 1, text
    assert text.startswith("Largest pressure (Pa):"), text


def test_21_an_unknown_model_is_said_beside_the_model_field(watched, server):
    page = open_explorer(watched, server.url)
    change(page, "#model", "nope")
    page.wait_for_selector("#err-model:not([hidden])")
    assert "nope" in page.locator("#err-model").inner_text()
    assert page.locator("#err-design").is_hidden()


# ------------------------------------------------------------------ 7: narrow screens
def test_7_the_plot_and_sketch_text_is_legible_at_400_px(browser, server):
    w = Watched(browser, server.url, width=400)
    try:
        page = open_explorer(w, server.url)
        page.wait_for_selector('#plot g[data-series^="fe-"]')
        sizes = page.evaluate("""() => ['#plot', '#sketch'].map(id => {
            const texts = [...document.querySelectorAll(id + ' text')];
            return Math.min(...texts.map(t => t.getBoundingClientRect().height)); })""")
        assert min(sizes) >= 10, sizes  # px on screen (was about 5)
        width = page.evaluate("document.getElementById('plot').clientWidth")
        view_w = float(page.get_attribute("#plot", "viewBox").split()[2])
        assert abs(view_w - width) <= 1
        assert page.evaluate("document.documentElement.scrollWidth") <= 400
        screenshot(page, "audit-plot-400")
        assert w.errors == []
    finally:
        w.close()


# ------------------------------------------------------------------ 8, 13: the link
def test_8_a_link_pasted_into_the_open_page_applies(watched, server):
    page = open_explorer(watched, server.url)
    page.evaluate("location.hash = '#W_mm=3&L_mm=12&t_mm=0.8&pair=1&max=3000'")
    wait_prediction(page, L_mm=12, t_mm=0.8)
    assert page.input_value("#L_mm") == "12" and page.input_value("#pair") == "1"
    assert page.evaluate("window.explorer.request.pressures_pa.at(-1)") == 3000
    assert "L_mm=12" in page.evaluate("location.hash")


def test_13_the_link_keeps_the_axes_and_the_nearest_count(watched, server):
    page = open_explorer(watched, server.url)
    change(page, "#nearby", "2")
    page.wait_for_function("location.hash.includes('near=2')")
    page.select_option("#x_axis", "volume_ul")
    page.wait_for_function("location.hash.includes('x=volume_ul')")
    force = page.evaluate("!document.querySelector('#y_axis option[value=force]').disabled")
    if force:
        page.select_option("#y_axis", "force")
        page.wait_for_function("location.hash.includes('y=force')")
    page.reload()
    page.wait_for_selector("body[data-ready=true]")
    page.wait_for_function("window.explorer.prediction")
    assert page.input_value("#nearby") == "2"
    assert page.input_value("#x_axis") == "volume_ul"
    if force:
        assert page.input_value("#y_axis") == "force"
        assert "force" in page.get_attribute("#plot", "aria-label")  # 19
        assert page.locator("#curve-h").inner_text() == "Volume - force curve"  # 24
    # the count kept: two nearest FE records (by force not drawn, nor in the legend: a
    # free-tip curve has no force, tests/test_explorer_audit_s41.py)
    page.wait_for_function("window.explorer.nearest.length === 2")


# ------------------------------------------------------------------ 9, 17, 19: inverse
CANDIDATE = {"rank": 1, "L_mm": 7.1, "t_mm": 0.5, "T_mm": 1.0, "b_mm": 1.8, "h_mm": 0.15,
             "body_material": "pdms_1_10", "membrane_material": "ecoflex_00_30",
             "body_stiffness_scale": 1.0, "membrane_stiffness_scale": 1.0, "score": 1.0,
             "pressure_needed_pa": 3900.0, "pressure_lower_pa": 3800.0,
             "pressure_upper_pa": 4000.0, "value_at_pressure": 30.0, "value_lower": 28.0,
             "value_upper": 32.0, "validity": {"in_domain": True, "flags": [], "messages": []},
             "curve": {}, "design": {"W_mm": 3.0}}


def fake_inverse(page, sent):
    def answer(route):
        sent.append(route.request.post_data_json)
        # (not a force message: an angle target's notes leave those out, hostile round 4)
        shared = "near FE curves that ended early at 1 pressure(s): the band is widened"
        first = {**CANDIDATE, "validity": {"in_domain": True, "flags": [],
                                           "messages": [shared]}}
        second = {**CANDIDATE, "rank": 2, "L_mm": 8.2, "validity": {
            "in_domain": True, "flags": [], "messages": [shared, "its own caution"]}}
        route.fulfill(json={"objective": "certainty", "feasible": True,
                            "explanation": "2 of 4328 evaluated designs meet the target.",
                            "candidates": [first, second], "best_reachable": {},
                            "n_evaluated": 4328})
    page.route("**/v1/inverse", answer)


def test_9_17_19_loading_an_inverse_design_shows_its_target_pressure(watched, server):
    page = open_explorer(watched, server.url)
    sent = []
    fake_inverse(page, sent)
    page.fill("#inv-pressure", "4000")
    page.fill("#inv-angle", "30")
    page.click("#inv-run")
    page.wait_for_selector("#inv-table tbody tr")
    explanation = page.locator("#inv-explanation").inner_text()
    assert explanation.count("4328") == 1, explanation  # 17: the count once
    # 17: a message every candidate carries is said once, not in every row
    assert explanation.count("ended early at 1 pressure(s)") == 1
    rows = page.locator("#inv-table tbody tr").all_inner_texts()
    assert not any("ended early" in r for r in rows) and "its own caution" in rows[1]
    names = page.eval_on_selector_all("#inv-table button",
                                      "bs => bs.map(b => b.getAttribute('aria-label'))")
    assert len(set(names)) == 2 and all(n.startswith("Load rank") for n in names)  # 19
    page.locator('#inv-table button[data-candidate="0"]').click()
    page.wait_for_function("window.explorer.request && window.explorer.request"
                           ".pressures_pa.at(-1) >= 4000 && window.explorer.prediction")
    grid = page.evaluate("window.explorer.request.pressures_pa")
    assert 4000 in grid
    assert page.locator("#p_op-out").inner_text().startswith("4000 Pa: angle")
    assert "4000" in page.locator("#view-note").inner_text()
    cursor = float(page.get_attribute("#plot line[data-cursor]", "data-cursor"))
    assert cursor == pytest.approx(4000)


def test_17_the_inverse_form_offers_only_what_the_server_takes(watched, server):
    page = open_explorer(watched, server.url)
    sent = []
    fake_inverse(page, sent)
    disabled = "(v) => document.querySelector(`#inv-objective option[value=${v}]`).disabled"
    assert page.evaluate(disabled, "pressure") and page.evaluate(disabled, "margin")
    page.select_option("#inv-kind", "pressure_budget")
    assert not page.evaluate(disabled, "pressure")
    page.select_option("#inv-objective", "pressure")
    page.select_option("#inv-kind", "angle_at_pressure")
    assert page.input_value("#inv-objective") == ""  # a refused ranking is not kept
    for k in range(4):
        page.uncheck(f"#inv-pair-{k}")
    page.click("#inv-run")
    page.wait_for_selector("#err-inv-pairs:not([hidden])")
    assert "at least one" in page.locator("#err-inv-pairs").inner_text()
    assert sent == []
    page.check("#inv-pair-0")
    page.fill("#inv-L-lo", "5")  # the other end empty: the box's edge
    page.click("#inv-run")
    page.wait_for_selector("#inv-table tbody tr")
    assert sent[-1]["L_bounds_mm"] == [5, 18]
    assert "t_bounds_mm" not in sent[-1]


# ------------------------------------------------------------------ 10: service stopped
def test_10_a_stopped_service_is_said_plainly_and_the_page_recovers(watched, server):
    page = open_explorer(watched, server.url)
    page.evaluate("window.explorer.retryMs = 400")
    page.route("**/v1/**", lambda route: route.abort())
    page.fill("#L_mm", "8")
    page.wait_for_function("document.getElementById('status').textContent"
                           ".includes('not answering')")
    assert "Failed to fetch" not in page.locator("#status").inner_text()
    assert "not answering" in page.locator("#health").inner_text()
    assert page.locator("#err-design").is_hidden()
    screenshot(page, "audit-service-down-1280")
    page.unroute("**/v1/**")  # back: the timer finds it
    wait_prediction(page, L_mm=8)
    assert "not answering" not in page.locator("#status").inner_text()
    page.wait_for_function("document.getElementById('health').textContent.includes('FE records')")
    # the default model is named, not only the exponential file ("surrogate fe-fit")
    health = page.locator("#health").inner_text()
    assert "emulator (default model)" in health and 'exponential model "' in health
    # and on returning to the tab, without waiting for the timer
    page.evaluate("window.explorer.retryMs = 600000")
    page.route("**/v1/**", lambda route: route.abort())
    page.fill("#L_mm", "9")
    page.wait_for_function("window.explorer.offline === true")
    page.unroute("**/v1/**")
    page.evaluate("window.dispatchEvent(new Event('focus'))")
    wait_prediction(page, L_mm=9)


# ------------------------------------------------------------------ 11, 24: FE solve
def test_11_24_an_fe_solve_that_ends_early_says_where_and_is_shown_after_a_reload(
        watched, server):
    page = open_explorer(watched, server.url)
    records = page.locator("#health").inner_text()
    page.fill("#L_mm", "3")  # refused by the emulator, solved by FE
    page.wait_for_selector("#refused:not([hidden])")
    assert page.locator("#pin").is_disabled()  # 16: nothing to pin
    page.wait_for_function("document.getElementById('mesh_level').max === '2'")  # the schema's
    page.fill("#api_key", API_KEY)
    page.fill("#mesh_level", "3")
    page.click("#solve")
    page.wait_for_selector("#err-settings:not([hidden])")
    assert "to 2" in page.locator("#err-settings").inner_text()
    assert page.locator("#job").inner_text() == ""  # not sent
    page.fill("#mesh_level", "0")
    page.click("#solve")
    page.wait_for_function("document.getElementById('job').dataset.status === 'finished'",
                           timeout=60_000)
    job = page.locator("#job").inner_text()
    assert "stops at 30.0 deg (3000 Pa)" in job and REASON in job, job
    assert not ("finished" in job and "failed" in job), job
    page.wait_for_selector('#plot g[data-series="fe-solve"]')
    # the readout and the sketch use the design's FE curve (1000 Pa: its second step)
    readout = page.locator("#p_op-out").inner_text()
    assert "FE curve: angle 10.0 deg" in readout, readout
    assert float(page.get_attribute("#sketch", "data-angle")) == pytest.approx(10.0)
    page.wait_for_function(f"document.getElementById('health').textContent !== {records!r}")
    screenshot(page, "audit-fe-solve-ended-early-1280")
    # after a reload the stored curve is drawn again, saying where it stops
    page.reload()
    page.wait_for_selector("body[data-ready=true]")
    page.wait_for_selector('#plot g[data-series="fe-solve"]')
    page.wait_for_selector("#fe-note:not([hidden])")
    assert "stops at 30.0 deg" in page.locator("#fe-note").inner_text()
    assert "stops at 30.0 deg" in " ".join(page.locator("#plot text").all_text_contents())


def test_11_the_job_line_says_when_the_solver_cuts_its_step_back(watched, server):
    page = open_explorer(watched, server.url)
    texts = page.evaluate("""async () => {
        const j = await import('/static/explorer/js/job.js');
        const step = (k, p, v) => ({step: k, pressure_pa: p, volume_ul: v, angle_deg: k,
                                    at_ms: 1000});
        const even = [1, 2, 3, 4, 5].map(k => step(k, 500 * k, k));
        const cut = [...even.slice(0, 4), step(5, 2050, 4.1)];
        const running = (trace) => j.jobText({status: 'running', progress: trace.at(-1)},
                                             trace, null, 2000);
        return [running(even), running(cut), j.cutBackText(even, {}, 30000),
                j.jobText({status: 'finished', curve_id: 'abc', curve_status: 'complete'}, [],
                          {angle_deg: 90, pressure_pa: 2400})];
    }""")
    even, cut, stalled, done = texts
    assert "cutting" not in even
    assert "cutting its step back" in cut and "50.0 Pa" in cut, cut
    assert "no new converged step for 29 s" in stalled
    assert done.startswith("FE solve done: the curve reaches 90.0 deg") and "abc" in done


# ------------------------------------------------------------------ 14, 15, 24: axes
def test_14_24_by_time_without_a_flow_rate_no_fe_curve_is_drawn_against_time(watched, server):
    page = open_explorer(watched, server.url)
    page.select_option("#ask_axis", "time_s")
    # the pressure plot's FE curves are there already: wait for the time plot itself
    page.wait_for_function("document.getElementById('curve-h').textContent"
                           " === 'Time - angle curve'")
    page.wait_for_selector('#plot g[data-series^="fe-"]')
    assert page.locator("#curve-h").inner_text() == "Time - angle curve"
    page.fill("#flow", "")
    page.dispatch_event("#flow", "change")
    page.wait_for_selector("#err-flow_ul_s:not([hidden])")
    page.wait_for_function("!document.querySelector('#plot g[data-series^=\"fe-\"]')")
    assert "at this time" in " ".join(page.locator("#sketch text").all_text_contents())


def test_15_the_x_axis_is_the_chamber_pressure_and_the_pump_gauge_can_be_plotted(
        watched, server):
    page = open_explorer(watched, server.url)
    assert "chamber pressure (Pa)" in page.locator("#plot").inner_html()
    page.check("#inlet")
    page.wait_for_function("window.explorer.prediction && window.explorer.prediction"
                           ".pump_pressure_pa")
    page.select_option("#x_axis", "pump_pressure_pa")
    drawn = json.loads(page.get_attribute('#plot g[data-series="prediction"]', "data-x"))
    pump = page.evaluate("window.explorer.prediction.pump_pressure_pa")
    assert drawn == pytest.approx(pump)
    assert "pump-gauge pressure (Pa)" in page.locator("#plot").inner_html()
    assert page.locator("#curve-h").inner_text() == "Pump-gauge pressure - angle curve"


# ------------------------------------------------------------------ 16: compare
def test_16_validity_flags_in_the_compare_table_are_words(watched, server):
    page = open_explorer(watched, server.url)
    page.fill("#t_mm", "0.55")
    change(page, "#p_max", "3000")
    page.wait_for_function("window.explorer.prediction && window.explorer.prediction"
                           ".pressure_pa.at(-1) === 3000")
    page.click("#pin")
    cell = page.locator("#compare-table tbody tr td").nth(5).inner_text()
    assert cell and "_" not in cell, cell
    flag = page.evaluate("async () => (await import('/static/explorer/js/app.js'))"
                         ".flagWords('force_band_too_wide')")
    assert flag == "force band too wide"


# ------------------------------------------------------------------ 22: no FE curves
def test_22_a_family_without_stored_fe_curves_is_said(watched, server):
    page = open_explorer(watched, server.url)
    page.fill("#T_mm", "1.23")  # no record has this body thickness
    wait_prediction(page, T_mm=1.23)
    page.wait_for_selector("#fe-note:not([hidden])")
    assert "No stored FE curves for this family" in page.locator("#fe-note").inner_text()
    page.fill("#T_mm", "1")
    page.wait_for_selector("#fe-note", state="hidden")


# ------------------------------------------------------------------ 23: readout slider
def test_23_the_readout_keeps_its_place_when_the_grid_end_changes(watched, server):
    page = open_explorer(watched, server.url)
    page.select_option("#ask_axis", "time_s")
    page.wait_for_function("window.explorer.request && window.explorer.request.times_s")
    for value in ("1000000", "100000", "20"):
        change(page, "#t_max", value)
    page.wait_for_function("window.explorer.request.times_s.at(-1) === 20"
                           " && window.explorer.prediction")
    assert page.locator("#p_op-out").inner_text().startswith("10.0 s:")


# ------------------------------------------------------------------ 3, 4, 12: calibration
REPORT = {"rmse_model_deg": 2.0, "rmse_before_deg": 1.5, "rmse_after_deg": 0.8,
          "noise_floor_deg": None, "selected_effects": [], "candidates": [],
          "residual_structured_after": False, "interpretation": "the fake report",
          "model": {"name": "emulator"}, "fitted": {"effects": {}}}


def test_3_4_12_calibration_errors_name_the_column_and_hide_the_old_report(
        watched, server, tmp_path):
    page = open_explorer(watched, server.url)
    calls = []

    def first_faked(route):  # the first calibration's report (slow work not under test)
        calls.append(route.request.post_data_json)
        if len(calls) == 1:
            route.fulfill(json=REPORT)
        else:
            route.continue_()

    page.route("**/v1/calibrate", first_faked)
    page.set_input_files("#cal-file", str(EXAMPLE_CSV))
    page.click("#cal-run")
    page.wait_for_selector("#cal-report:not([hidden])")
    # 4: a report with no per-family constants (a calibration against the emulator) is
    # saved since 2026-12-06 (surrogate/calibration/_saved_design.py): Save stays open
    assert page.locator("#save-run").is_enabled()
    assert page.locator("#cal-save-note").is_hidden()
    # 3 and 12: a file without angle_deg, then one with a word in it
    lines = [x for x in EXAMPLE_CSV.read_text().splitlines()
             if x.strip() and not x.startswith("#")]
    header = lines[0].split(",")
    k = header.index("angle_deg")
    missing = tmp_path / "missing.csv"
    missing.write_text("\n".join(",".join(c for j, c in enumerate(x.split(",")) if j != k)
                                 for x in lines[:20]) + "\n")
    page.set_input_files("#cal-file", str(missing))
    page.click("#cal-run")
    page.wait_for_selector("#err-cal-rows:not([hidden])")
    assert page.locator("#cal-report").is_hidden()
    assert "angle_deg" in page.locator("#err-cal-rows").inner_text()
    bad = tmp_path / "bad.csv"
    rows = [x.split(",") for x in lines[:20]]
    rows[2][k] = "abc"
    bad.write_text("\n".join(",".join(r) for r in rows) + "\n")
    page.set_input_files("#cal-file", str(bad))
    page.click("#cal-run")
    page.wait_for_function("document.getElementById('err-cal-rows').textContent.includes('abc')")
    text = page.locator("#err-cal-rows").inner_text()
    assert "column angle_deg" in text and "row 2" in text, text
    assert page.locator("#cal-report").is_hidden()


def test_4_a_refused_save_is_remembered_before_the_next_calibration(watched, server):
    page = open_explorer(watched, server.url)
    refusal = {"type": "urn:balloon:problem:invalid-input", "title": "Invalid input",
               "status": 422, "detail": "save: ...",
               "errors": [{"loc": ["body", "save"], "field": "save",
                           "message": "a calibration against 'lab0' cannot be saved yet "
                                      "(saved models hold per-family exponential constants)"}]}
    page.route("**/v1/calibrate", lambda route: route.fulfill(
        status=422, json=refusal, headers={"Content-Type": "application/problem+json"}))
    page.fill("#cal-model", "lab0")
    page.set_input_files("#cal-file", str(EXAMPLE_CSV))
    page.click("#cal-run")
    page.wait_for_selector("#cal-save-note:not([hidden])")
    assert "per-family exponential constants" in page.locator("#cal-save-note").inner_text()


def test_4_a_report_that_cannot_be_saved_greys_out_save_at_once(watched, server):
    """The report says whether it can be saved (``saveable``): the page greys out Save
    with the server's words, without a refused save first."""
    page = open_explorer(watched, server.url)
    why = ("the calibration leaves structure in the angle that its selected effects do "
           "not explain: a saved model would not stand for your actuators")
    page.route("**/v1/calibrate", lambda route: route.fulfill(
        json={**REPORT, "residual_structured_after": True,
              "saveable": {"ok": False, "why": why}}))
    page.set_input_files("#cal-file", str(EXAMPLE_CSV))
    page.click("#cal-run")
    page.wait_for_selector("#cal-report:not([hidden])")
    page.wait_for_function("document.getElementById('save-run').disabled")
    assert "leaves structure in the angle" in page.locator("#save-note").inner_text()
    screenshot(page, "audit-calibration-unsaveable-1280")
    # a report that can be saved leaves Save open
    page.unroute("**/v1/calibrate")
    page.route("**/v1/calibrate", lambda route: route.fulfill(
        json={**REPORT, "saveable": {"ok": True, "why": None}}))
    page.click("#cal-run")
    page.wait_for_function("!document.getElementById('save-run').disabled")
    assert page.locator("#save-note").is_hidden()
