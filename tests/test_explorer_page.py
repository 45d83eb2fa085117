"""The design explorer at / in real headless Chromium: it loads with no console error and
no request off the server, redraws the curve with /v1/predict's own numbers as the L slider
moves, pins and exports curves, says the validity flags in words, and renders the fields
the predictor is gaining (force, volume, capped angles) when a response carries them.
Screenshots at 1280 and 800 px: test-artifacts/explorer/."""

from __future__ import annotations

import csv
import io
import json

import httpx
import pytest
from explorer_browser import (
    LiveServer,
    Watched,
    hold_predict,
    open_explorer,
    release,
    screenshot,
    wait_held,
)

GRID_POINTS = 81  # the page's pressure grid: 0 .. p_max in 80 steps


pytestmark = pytest.mark.timeout(300)  # a browser that hangs fails the test

@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with LiveServer(tmp_path_factory.mktemp("explorer-page")) as live:
        yield live




def grid(p_max: float) -> list[float]:
    return [p_max * i / (GRID_POINTS - 1) for i in range(GRID_POINTS)]


def series(page, name: str) -> dict:
    g = page.locator(f'#plot g[data-series="{name}"]')
    return {"x": json.loads(g.get_attribute("data-x")), "y": json.loads(g.get_attribute("data-y"))}


def wait_prediction(page, **design):
    cond = " && ".join(f"p.design.{k} === {v}" for k, v in design.items())
    page.wait_for_function(
        f"(() => {{ const p = window.explorer.prediction; return p && {cond}; }})()")


def test_page_loads_offline_with_no_console_error_at_both_widths(browser, server):
    for width in (1280, 800):
        w = Watched(browser, server.url, width=width)
        try:
            page = open_explorer(w, server.url)
            page.wait_for_selector('#plot g[data-series^="fe-"]')  # nearest FE curves drawn
            page.wait_for_selector('#plot g[data-series="prediction"] path.line')
            assert page.locator("#plot polygon.band").count() >= 1
            assert "angle" in page.locator("#p_op-out").inner_text()
            assert page.locator("#sketch polygon[data-part=body]").count() == 1
            overflow = page.evaluate("document.documentElement.scrollWidth")
            screenshot(page, f"explorer-{width}")
            assert w.errors == [], w.errors
            assert w.foreign_requests() == [], w.foreign_requests()
            assert overflow <= width, f"page is {overflow} px wide at {width} px"
            assert any("/v1/predict" in u for u in w.requests)
        finally:
            w.close()


def test_the_nearest_fe_curves_are_labelled_with_their_materials(watched, server):
    page = open_explorer(watched, server.url)
    page.wait_for_selector('#plot g[data-series^="fe-"]')
    labels = [x for x in page.locator("#plot text").all_text_contents() if x.startswith("FE ")]
    assert labels and all(x.startswith("FE PDMS 1:10 / Ecoflex 00-30, L=") for x in labels), labels
    # a stored stiffness-scaled layer ("<preset>*<s>") and the page's inline one
    # ("<preset>_x<s>", scale read off the moduli) carry their scale; a scale of 1 none
    got = page.evaluate("""async () => {
        const d = await import("/static/explorer/js/design.js");
        const presets = window.explorer.presets;
        const inline = d.material("pdms_1_15", 0.5, presets);
        return [d.materialLabel("pdms_1_15*0.967705"), d.materialLabel(inline, presets),
                d.materialLabel("ecoflex_00_30", presets),
                d.materialLabel({id: "pdms_1_10", mu_kpa: presets.pdms_1_10.mu_kpa,
                                 alpha: presets.pdms_1_10.alpha}, presets)];
    }""")
    assert got == ["PDMS 1:15 x0.968", "PDMS 1:15 x0.5", "Ecoflex 00-30", "PDMS 1:10"]
    assert watched.errors == []


def test_moving_the_L_slider_redraws_the_curve_with_the_numbers_of_v1_predict(watched, server):
    page = open_explorer(watched, server.url)
    before = page.locator('#plot g[data-series="prediction"] path.line').get_attribute("d")
    page.focus("#L_mm-range")
    for _ in range(10):  # 10 steps of 0.1 mm: 7.1 -> 8.1
        page.keyboard.press("ArrowRight")
    wait_prediction(page, L_mm=8.1)
    page.wait_for_function("window.explorer.timings.length > 0")
    assert page.input_value("#L_mm") == "8.1"
    after = page.locator('#plot g[data-series="prediction"] path.line').get_attribute("d")
    assert after != before
    drawn = series(page, "prediction")
    body = {"design": {"L_mm": 8.1, "t_mm": 0.5, "T_mm": 1.0, "b_mm": 1.8, "h_mm": 0.15,
                       "W_mm": 3.0, "body_material": "pdms_1_10",
                       "membrane_material": "ecoflex_00_30"},
            "pressures_pa": grid(2000.0), "model": "emulator", "level": 0.95}
    api = httpx.post(server.url + "/v1/predict", json=body).json()
    assert drawn["x"] == pytest.approx(api["pressure_pa"], abs=1e-9)
    assert drawn["y"] == pytest.approx(api["angle_deg"], abs=1e-9)
    # the pressure readout shows the API's value at the slider's pressure (1000 Pa)
    i = 40
    assert f"angle {api['angle_deg'][i]:.1f} deg" in page.locator("#p_op-out").inner_text()
    assert float(page.locator("#sketch").get_attribute("data-angle")) == pytest.approx(
        api["angle_deg"][i])
    assert watched.errors == []


def test_a_new_width_scales_the_design_and_its_ranges_and_the_curve_is_the_scaled_copys(
        watched, server):
    """W = 6 mm: every length doubles (a scaled copy), the lengths' ranges are the box at W =
    3 mm doubled, the drawn curve is /v1/predict's for the doubled design (the same angle at
    each pressure as at W = 3 mm, 8 x the volume), the nearest FE records are drawn scaled
    with their scale in the label; Reset returns to W = 3 mm."""
    page = open_explorer(watched, server.url)
    page.wait_for_selector('#plot g[data-series^="fe-"]')
    standard = series(page, "prediction")
    fe_before = page.locator('#plot g[data-series^="fe-"]').first.get_attribute("data-series")
    page.fill("#W_mm", "6")
    wait_prediction(page, W_mm=6)
    assert page.input_value("#L_mm") == "14.2"
    assert page.input_value("#t_mm") == "1"
    assert page.input_value("#h_mm") == "0.3"
    assert page.get_attribute("#L_mm", "max") == "36"
    assert page.get_attribute("#L_mm-range", "min") == "8"
    assert page.locator("#L_mm-range-text").inner_text() == "8 - 36 mm"
    assert page.get_attribute("#body_scale", "max") == "100"  # the stiffness scales keep theirs
    drawn = series(page, "prediction")
    body = {"design": {"L_mm": 14.2, "t_mm": 1.0, "T_mm": 2.0, "b_mm": 3.6, "h_mm": 0.3,
                       "W_mm": 6.0, "body_material": "pdms_1_10",
                       "membrane_material": "ecoflex_00_30"},
            "pressures_pa": grid(2000.0), "model": "emulator", "level": 0.95}
    api = httpx.post(server.url + "/v1/predict", json=body).json()
    assert drawn["y"] == pytest.approx(api["angle_deg"], abs=1e-9)
    assert drawn["y"] == pytest.approx(standard["y"], abs=1e-6)  # the scaled copy's curve
    pred = page.evaluate("window.explorer.prediction")
    base = httpx.post(server.url + "/v1/predict", json={**body, "design": {
        **body["design"], "L_mm": 7.1, "t_mm": 0.5, "T_mm": 1.0, "b_mm": 1.8, "h_mm": 0.15,
        "W_mm": 3.0}}).json()
    i = 40
    assert pred["volume_ul"][i] == pytest.approx(8 * base["volume_ul"][i], rel=1e-6)
    page.wait_for_function("[...document.querySelectorAll('#plot text')].some("
                           "t => t.textContent.includes('scaled x2'))")
    fe = page.locator('#plot g[data-series^="fe-"]').first
    assert fe.get_attribute("data-series") == fe_before  # the same records, scaled
    screenshot(page, "explorer-width-6mm")
    page.click("#reset")
    wait_prediction(page, W_mm=3)
    assert page.input_value("#L_mm") == "7.1"
    assert page.get_attribute("#L_mm", "max") == "18"
    assert watched.errors == []


def test_the_address_holds_the_view_and_a_link_reopens_it(watched, server):
    """A page opened with a fragment starts from its design and curve request; every answer
    rewrites the fragment; a hostile fragment's unknown keys and bad values are ignored and
    named, never interpreted."""
    page = watched.page
    page.goto(server.url + "/#W_mm=6&L_mm=20&t_mm=1.2&T_mm=2.4&b_mm=3&h_mm=0.4&pair=2"
              "&ask=volume_ul&max=40&flow=5&model=emulator")
    page.wait_for_selector("body[data-ready=true]")
    wait_prediction(page, W_mm=6, L_mm=20)
    assert page.input_value("#W_mm") == "6" and page.input_value("#t_mm") == "1.2"
    assert page.input_value("#pair") == "2" and page.input_value("#ask_axis") == "volume_ul"
    assert page.get_attribute("#L_mm", "max") == "36"  # the ranges at W = 6 mm
    request = page.evaluate("window.explorer.request")
    assert request["volumes_ul"][-1] == pytest.approx(40) and request["flow_ul_s"] == 5
    assert request["design"]["body_material"] == "ecoflex_00_30"
    assert request["design"]["membrane_material"] == "pdms_1_15"
    assert page.locator("#link-note").is_hidden()
    # a moved slider rewrites the fragment: the link reopens what is shown
    page.focus("#L_mm-range")
    page.keyboard.press("ArrowRight")
    wait_prediction(page, L_mm=20.1)
    page.wait_for_function("location.hash.includes('L_mm=20.1')")
    link = page.evaluate("location.href")
    assert "ask=volume_ul" in link and "W_mm=6" in link and "pair=2" in link
    again = watched.page.context.new_page()
    try:
        again.goto(link)
        again.wait_for_selector("body[data-ready=true]")
        again.wait_for_function("window.explorer.prediction && "
                                "window.explorer.prediction.design.L_mm === 20.1")
        assert again.evaluate("window.explorer.request") == page.evaluate(
            "window.explorer.request")
    finally:
        again.close()
    # hostile: unknown keys, non-numbers, an out-of-list pair and axis, a path as model;
    # opened in a new page, and pasted into the open one (applied at once: hashchange)
    hostile = (server.url + "/#L_mm=%3Cimg%20src%3Dx%20onerror%3Dalert(1)%3E&pair=9&foo=1"
               "&ask=bogus&model=..%2F..%2Fetc&t_mm=-1&W_mm=Infinity")
    fresh = watched.page.context.new_page()
    for tab in (fresh, page):
        tab.goto(hostile)
        tab.wait_for_selector("body[data-ready=true]")
        tab.wait_for_function("document.getElementById('link-note').textContent.includes('foo')")
        wait_prediction(tab, L_mm=7.1, W_mm=3)
        note = tab.locator("#link-note").inner_text()
        for key in ("L_mm", "pair", "foo", "ask", "model", "t_mm", "W_mm"):
            assert key in note, (key, note)
        assert tab.locator("img").count() == 0
        assert tab.input_value("#pair") == "0" and tab.input_value("#t_mm") == "0.5"
    fresh.close()
    assert watched.errors == []


def test_a_stale_prediction_is_cancelled_and_never_drawn_over_a_newer_one(watched, server):
    page = open_explorer(watched, server.url)
    failed = []
    page.on("requestfailed",
            lambda r: failed.append(r.post_data_json) if "/v1/predict" in r.url else None)
    held = hold_predict(page)  # answered only after the newer request has been drawn
    page.fill("#L_mm", "9")
    first = wait_held(page, held, "the first prediction request")
    page.fill("#L_mm", "10")
    wait_prediction(page, L_mm=10)
    release(first)
    page.wait_for_timeout(500)
    assert page.evaluate("window.explorer.prediction.design.L_mm") == 10
    assert [b["design"]["L_mm"] for b in failed] == [9]  # aborted by the page
    api = httpx.post(server.url + "/v1/predict", json={
        "design": {"L_mm": 10}, "pressures_pa": grid(2000.0)}).json()
    assert series(page, "prediction")["y"] == pytest.approx(api["angle_deg"], abs=1e-9)


def test_pinned_designs_overlay_and_export_as_csv_json_svg_png(watched, server):
    page = open_explorer(watched, server.url)
    page.click("#pin")
    page.fill("#L_mm", "12")
    wait_prediction(page, L_mm=12)
    page.click("#pin")
    page.fill("#t_mm", "0.8")
    wait_prediction(page, t_mm=0.8)
    assert page.locator("#compare-table tbody tr").count() == 2
    assert page.locator('#plot g[data-series="pin-1"]').count() == 1
    assert page.locator('#plot g[data-series="pin-2"]').count() == 1
    pinned = series(page, "pin-2")["y"]
    api = httpx.post(server.url + "/v1/predict", json={
        "design": {"L_mm": 12, "t_mm": 0.5}, "pressures_pa": grid(2000.0)}).json()
    assert pinned == pytest.approx(api["angle_deg"], abs=1e-9)
    row = page.locator("#compare-table tbody tr").nth(1).inner_text()
    assert f"{api['angle_deg'][40]:.1f} deg" in row

    with page.expect_download() as d:
        page.click("#export-csv")
    rows = list(csv.DictReader(io.StringIO(open(d.value.path()).read())))
    labels = {r["series"] for r in rows}
    assert len([x for x in labels if x.startswith("#")]) == 2 and any("model" in x for x in labels)
    model = [r for r in rows if "model" in r["series"]]
    assert len(model) == GRID_POINTS and float(model[-1]["pressure_pa"]) == 2000.0
    with page.expect_download() as d:
        page.click("#export-json")
    data = json.loads(open(d.value.path()).read())
    assert data["prediction"]["design"]["t_mm"] == 0.8 and len(data["pinned"]) == 2
    with page.expect_download() as d:
        page.click("#export-svg")
    svg = open(d.value.path()).read()
    assert "<svg" in svg and 'data-series="prediction"' in svg
    with page.expect_download() as d:
        page.click("#export-png")
    png = open(d.value.path(), "rb").read()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 5000
    page.click('#compare-table button[data-load="1"]')  # loads the first pinned design back
    wait_prediction(page, L_mm=7.1, t_mm=0.5)
    for L in (9, 10):  # four pinned at most
        page.fill("#L_mm", str(L))
        wait_prediction(page, L_mm=L)
        page.click("#pin")
    assert page.locator("#compare-table tbody tr").count() == 4
    assert page.locator("#pin").is_disabled()
    page.click('#compare-table button[data-unpin="2"]')
    assert page.locator("#compare-table tbody tr").count() == 3
    assert page.locator('#plot g[data-series="pin-2"]').count() == 0
    assert page.locator("#pin").is_enabled()
    screenshot(page, "explorer-compare-1280")
    assert watched.errors == []


def test_every_control_is_labelled_and_the_design_panel_works_from_the_keyboard(watched, server):
    page = open_explorer(watched, server.url)
    unlabelled = page.evaluate("""[...document.querySelectorAll('input, select, button')]
        .filter(e => !e.hidden && !(e.labels && e.labels.length) && !e.getAttribute('aria-label')
                     && !(e.tagName === 'BUTTON' && e.textContent.trim()))
        .map(e => e.id || e.outerHTML)""")
    assert unlabelled == []
    page.focus("#L_mm")
    page.keyboard.press("Tab")  # L number box -> t slider
    assert page.evaluate("document.activeElement.id") == "t_mm-range"
    page.keyboard.press("ArrowRight")  # 0.5 -> 0.51 mm
    wait_prediction(page, t_mm=0.51)
    page.focus("#pin")
    page.keyboard.press("Enter")
    assert page.locator("#compare-table tbody tr").count() == 1


def test_an_out_of_range_field_is_refused_beside_it_with_its_allowed_range(watched, server):
    page = open_explorer(watched, server.url)
    page.fill("#L_mm", "70")  # the number box takes any value; the server names the limit
    page.wait_for_selector("#err-L_mm:not([hidden])")
    problem = httpx.post(server.url + "/v1/predict", json={
        "design": {"L_mm": 70}, "pressures_pa": [0]}).json()
    allowed = problem["errors"][0]["allowed"]
    # the server's range in the page's words: its field named as the box's label
    text = page.locator("#err-L_mm").inner_text()
    assert allowed.replace("L_mm", "Chamber length L (mm)") in text and "L_mm" not in text
    assert page.get_attribute("#L_mm", "aria-invalid") == "true"
    assert page.locator("#refused").is_hidden()  # a range error is not offered an FE solve
    page.fill("#L_mm", "7.1")
    page.wait_for_selector("#err-L_mm", state="hidden")
    assert page.get_attribute("#L_mm", "aria-invalid") is None


def _set_largest(page, field: str, value: str, ready: str) -> None:
    """Type the curve's largest pressure or volume, commit it, and wait until ``ready``
    (a JavaScript condition on window.explorer) holds."""
    page.fill(field, value)
    page.dispatch_event(field, "change")
    page.wait_for_function(ready)


def test_validity_flags_and_messages_are_shown_in_words(watched, server):
    page = open_explorer(watched, server.url)
    page.fill("#t_mm", "0.55")
    _set_largest(page, "#p_max", "3000", "window.explorer.prediction"
                 " && window.explorer.prediction.pressure_pa.at(-1) === 3000")
    api = httpx.post(server.url + "/v1/predict", json={
        "design": {"L_mm": 7.1, "t_mm": 0.55}, "pressures_pa": grid(3000.0)}).json()
    assert api["validity"]["messages"], "the design should be flagged past the FE range"
    shown = page.locator("#validity li").all_inner_texts()
    for message in api["validity"]["messages"]:
        assert message in shown
    # flagged: said as a caution (the server's in_domain may be true or false here)
    assert page.locator("#validity p.warn").count() >= 1
    assert page.locator("#validity .chip").count() == len(api["validity"]["flags"])


def test_force_volume_and_capped_angles_are_rendered_when_the_response_has_them(watched, server):
    """The predictor is gaining force_mn, volume_ul and null angles past the FE's range: the
    real /v1/predict answer, extended in the browser by route interception, is rendered."""
    page = watched.page

    def extend(route):
        body = route.fetch().json()
        n = len(body["pressure_pa"])
        body["volume_ul"] = [p / 1000 for p in body["pressure_pa"]]
        body["force_mn"] = [p / 100 for p in body["pressure_pa"]]
        body["force_lower_mn"] = [p / 120 for p in body["pressure_pa"]]
        body["force_upper_mn"] = [p / 80 for p in body["pressure_pa"]]
        for key in ("angle_deg", "lower_deg", "upper_deg"):
            body[key] = [None if i > n - 10 else v for i, v in enumerate(body[key])]
        route.fulfill(json=body)

    page.route("**/v1/predict", extend)
    open_explorer(watched, server.url)
    assert "force 10.0 mN" in page.locator("#p_op-out").inner_text()
    assert "volume 1.00 ul" in page.locator("#p_op-out").inner_text()
    assert any("capped" in t for t in page.locator("#validity li").all_inner_texts())
    page.select_option("#x_axis", "volume_ul")
    assert series(page, "prediction")["x"][-1] == pytest.approx(2.0)
    page.select_option("#y_axis", "force")
    assert series(page, "prediction")["y"][-1] == pytest.approx(20.0)
    # the angle curve is broken, not drawn to zero, where the answer is capped
    page.select_option("#y_axis", "angle")
    assert series(page, "prediction")["y"][-1] is None
    assert watched.errors == []


def test_the_ask_axis_switch_asks_by_volume_and_by_time_at_the_flow_rate(watched, server):
    """The syringe-pump view: the page asks /v1/predict by injected volume, then by time at
    the pump's flow rate, and draws the API's own numbers against the asked axis."""
    page = open_explorer(watched, server.url)
    sent = []
    page.on("request", lambda r: sent.append(r.post_data_json)
            if "/v1/predict" in r.url and r.method == "POST" else None)
    page.select_option("#ask_axis", "volume_ul")
    page.wait_for_function("window.explorer.request && window.explorer.request.volumes_ul"
                           " && window.explorer.prediction.volume_ul")
    assert page.locator("#v_max").is_visible() and page.locator("#p_max").is_hidden()
    assert page.input_value("#x_axis") == "volume_ul"
    body = sent[-1]
    assert "pressures_pa" not in body and body["flow_ul_s"] == 2.5
    assert body["volumes_ul"] == pytest.approx(grid(50.0))
    api = httpx.post(server.url + "/v1/predict", json=body).json()
    drawn = series(page, "prediction")
    assert drawn["x"] == pytest.approx(api["volume_ul"], abs=1e-9)
    assert drawn["y"] == pytest.approx(api["angle_deg"], abs=1e-9)
    readout = page.locator("#p_op-out").inner_text()
    assert readout.startswith("25.00 ul: angle") and "chamber pressure" in readout
    assert f"angle {api['angle_deg'][40]:.1f} deg" in readout
    assert "time 10.0 s" in readout  # 25 ul at 2.5 ul/s

    page.select_option("#ask_axis", "time_s")
    page.fill("#t_max", "10")
    page.dispatch_event("#t_max", "change")
    page.check("#inlet")
    page.wait_for_function("(() => { const r = window.explorer.request; return r && r.times_s"
                           " && r.times_s.at(-1) === 10 && r.inlet"
                           " && window.explorer.prediction.pump_pressure_pa; })()")
    body = sent[-1]
    assert body["times_s"] == pytest.approx(grid(10.0)) and body["inlet"] == {}
    api = httpx.post(server.url + "/v1/predict", json=body).json()
    assert page.input_value("#x_axis") == "time_s"
    drawn = series(page, "prediction")
    assert drawn["x"] == pytest.approx(api["time_s"], abs=1e-9)
    assert drawn["y"] == pytest.approx(api["angle_deg"], abs=1e-9)
    readout = page.locator("#p_op-out").inner_text()
    i = round(float(page.input_value("#p_op")) / 10 * (GRID_POINTS - 1))  # the slider's point
    assert readout.startswith(f"{api['time_s'][i]:.1f} s: angle")
    assert f"pump gauge {api['pump_pressure_pa'][i]:.0f} Pa" in readout
    # the nearest FE curves are drawn on the same clock: their volume over the flow rate
    page.wait_for_selector('#plot g[data-series^="fe-"]')
    fe = series(page, page.locator('#plot g[data-series^="fe-"]').first.get_attribute(
        "data-series"))
    assert max(x for x in fe["x"] if x is not None) <= 10 * 1.05
    # a time without a flow rate: the server's problem is shown beside the flow field
    page.fill("#flow", "")
    page.dispatch_event("#flow", "change")
    page.wait_for_selector("#err-flow_ul_s:not([hidden])")
    text = page.locator("#err-flow_ul_s").inner_text()   # named by the page's controls
    assert "Pump flow rate (ul/s) <= 1000 ul/s" in text and "flow_ul_s" not in text, text
    assert 'with Ask by "time at the pump\'s flow rate (s)"' in text, text
    screenshot(page, "explorer-by-time-1280")
    page.fill("#flow", "2.5")
    page.dispatch_event("#flow", "change")
    page.select_option("#ask_axis", "pressure_pa")
    page.wait_for_function("window.explorer.request && window.explorer.request.pressures_pa")
    assert page.input_value("#x_axis") == "pressure_pa"
    # the one console line is the browser's note of the refused (422) request
    assert [e for e in watched.errors if "422" not in e] == []


def test_where_the_curve_ends_is_said_with_the_servers_number(watched, server):
    # the page said "from 39.38 ul" (its first empty grid point) beside the server's
    # "above 38.8 ul" (an audit of the thirty-fifth session)
    page = open_explorer(watched, server.url)
    page.select_option("#ask_axis", "volume_ul")
    _set_largest(page, "#v_max", "200", "window.explorer.request"
                 " && window.explorer.request.volumes_ul"
                 " && window.explorer.request.volumes_ul.at(-1) === 200"
                 " && window.explorer.prediction.angle_deg.includes(null)")
    end = page.evaluate("window.explorer.prediction.validity.fe_limit_volume_ul")
    assert f"The curve ends at {end:.2f} ul" in page.locator("#validity").inner_text()
