"""The explorer's fixes from the fiftieth session's page-and-batch audit, in real headless
Chromium on one live server (the shipped emulator and database; FE solves faked by
``service_solves.landing_solve``, a stored curve at 0, 10, 40, 90 deg by 0, 1000, 2000,
2900 Pa, in real worker processes):

- a refusal names the page's own control, never the request's field: the paper's model
  asked by time said "allowed: pressures_pa" beside "Largest time (s)"; asked by
  pressure it refused every design for the page's default pump flow rate;
- the FE readout reads the design's FE curve at the asked value, between its steps, and
  says when the value is past the curve's end (it showed the nearest step's angle);
- the CSV and JSON exports name the model file by its SHA-256 and the service's version;
- every number box of the Curve panel, the solve's mesh level, the search's count and the
  calibration's folds show their range before anything is typed (they showed it only in
  the error of a value out of it).

Screenshots: test-artifacts/explorer/s50-*.png.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
from pathlib import Path

import pytest
from explorer_browser import LiveServer, change, open_explorer, screenshot, solved_refused_design
from service_solves import landing_solve

pytestmark = pytest.mark.timeout(300)


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with LiveServer(tmp_path_factory.mktemp("explorer-s50"), solve_fn=landing_solve) as live:
        yield live


def test_the_papers_refusal_by_time_names_the_pages_controls_not_the_apis(watched, server):
    page = open_explorer(watched, server.url)
    page.select_option("#ask_axis", "time_s")
    change(page, "#model", "paper")
    page.wait_for_selector("#err-ask_axis:not([hidden])")
    text = page.inner_text("#err-ask_axis")
    screenshot(page, "s50-paper-by-time")
    assert text.startswith("Ask by:"), text
    # the page's control and its range in the user's units, not the request's field
    assert "pressures_pa" not in text and "times_s" not in text, text
    assert 'allowed: Ask by "chamber pressure (Pa)"' in text, text
    assert 'Model "emulator"' in text, text
    # said once, beside "Ask by", not again beside the largest time's box
    assert page.locator("#err-times_s").is_hidden()
    # asked by pressure, the paper's model answers and the refusal goes; the page's pump
    # flow rate (2.5 ul/s, for the time axis) is left out for a model with no volumes,
    # saying so: it was refused beside "Pump flow rate" for every design
    page.select_option("#ask_axis", "pressure_pa")
    page.wait_for_function("window.explorer.prediction && window.explorer.prediction.model"
                           " === 'paper'")
    assert page.locator("#err-ask_axis").is_hidden()
    assert page.locator("#err-flow_ul_s").is_hidden()
    assert "no time axis" in page.inner_text("#status")
    assert page.input_value("#flow") == "2.5"   # the user's value kept


def test_the_fe_readout_reads_the_fe_curve_between_its_steps_and_past_its_end(
        watched, server):
    page = solved_refused_design(watched, server.url)
    # 1500 Pa on the 0..2000 Pa grid: halfway between the steps at 1000 (10 deg) and
    # 2000 Pa (40 deg): 25 deg, not the nearest step's 10
    page.fill("#p_op", "1500")
    page.dispatch_event("#p_op", "input")
    readout = page.inner_text("#p_op-out")
    assert "FE curve: angle 25.0 deg" in readout, readout
    assert "between its steps at 1000 and 2000 Pa" in readout, readout
    assert float(page.get_attribute("#sketch", "data-angle")) == pytest.approx(25.0)
    # 2450 Pa (the grid to 4000 Pa): between 2000 and 2900 Pa, 40 + 50 x 450 / 900 deg
    change(page, "#p_max", "4000")
    page.wait_for_function("document.getElementById('p_op').max === '4000'")
    page.fill("#p_op", "2450")
    page.dispatch_event("#p_op", "input")
    readout = page.inner_text("#p_op-out")
    assert "FE curve: angle 65.0 deg" in readout, readout
    # past the curve's end (2900 Pa): said, with where it stops; no angle read
    page.fill("#p_op", "3000")
    page.dispatch_event("#p_op", "input")
    readout = page.inner_text("#p_op-out")
    screenshot(page, "s50-fe-readout-past-end")
    assert "past the FE curve's end: it stops at 90.0 deg at 2900 Pa" in readout, readout
    assert "FE curve: angle" not in readout


HINTED = {"p_max": "from 100 to 20000 Pa", "nearby": "a whole number from 0 to 6",
          "mesh_level": "a whole number from 0 to 2", "inv-n": "a whole number from 1 to 20",
          "cal-folds": "a whole number from 2 to 50"}


def test_every_counted_box_shows_its_range_before_anything_is_typed(watched, server):
    page = open_explorer(watched, server.url)
    # the schema's limits (mesh level 0..2 from SolveSettingsIn) once it is read
    page.wait_for_function("document.getElementById('mesh_level-hint')?.textContent"
                           ".includes('to 2')")
    for box, words in HINTED.items():
        hint = page.locator(f"#{box}-hint")
        assert hint.count() == 1, box
        assert hint.text_content() == words, (box, hint.text_content())
        # tied to its box for a screen reader
        assert f"{box}-hint" in (page.get_attribute(f"#{box}", "aria-describedby") or "")
    page.select_option("#ask_axis", "volume_ul")
    assert page.locator("#v_max-hint").is_visible()
    assert "ul" in page.locator("#v_max-hint").text_content()
    page.fill("#L_mm", "3")  # refused: the solve box with its mesh level shows
    page.wait_for_selector("#refused:not([hidden])")
    assert page.locator("#mesh_level-hint").is_visible()
    screenshot(page, "s50-range-hints")
    # an error beside a box keeps the hint tied to it
    change(page, "#nearby", "9")
    page.wait_for_selector("#err-nearby:not([hidden])")
    described = page.get_attribute("#nearby", "aria-describedby").split()
    assert "nearby-hint" in described and "err-nearby" in described
    change(page, "#nearby", "2")
    page.wait_for_selector("#err-nearby", state="hidden")
    assert page.get_attribute("#nearby", "aria-describedby") == "nearby-hint"


def test_a_design_search_refusal_names_the_forms_boxes_not_the_apis_fields(watched, server):
    """The server's checks of a pump's target (the FE's 500 ul volume stop) said
    "allowed: 0 < volume_ul <= 500" and "time_s x flow_ul_s <= 500 ul" beside the boxes."""
    page = open_explorer(watched, server.url)
    page.select_option("#inv-kind", "angle_at_volume")
    page.fill("#inv-volume", "600")
    page.click("#inv-run")
    page.wait_for_selector("#err-inv-volume:not([hidden])")
    text = page.inner_text("#err-inv-volume")
    assert "volume_ul" not in text and "0 < Injected volume (ul) <= 500" in text, text
    page.select_option("#inv-kind", "angle_at_time")
    page.fill("#inv-time", "600")
    page.fill("#inv-flow", "2.5")
    page.click("#inv-run")
    page.wait_for_selector("#err-inv-time:not([hidden])")
    text = page.inner_text("#err-inv-time")
    screenshot(page, "s50-search-refusal-words")
    assert "time_s" not in text and "flow_ul_s" not in text, text
    assert "Time from empty (s) <= 200 s at 2.5 ul/s" in text, text
    assert "Pump flow rate (ul/s)" in text, text


def test_the_exports_name_the_model_file_and_the_version(watched, server):
    page = open_explorer(watched, server.url)
    page.wait_for_selector('#plot g[data-series^="fe-"]')
    page.wait_for_function("window.explorer.health !== null")
    sha = hashlib.sha256((Path(__file__).resolve().parent.parent / "service" / "data"
                          / "emulator.json").read_bytes()).hexdigest()
    with page.expect_download() as d:
        page.click("#export-csv")
    rows = list(csv.DictReader(io.StringIO(open(d.value.path()).read())))
    model = [r for r in rows if r["series"].startswith("model")]
    fe = [r for r in rows if r["series"].startswith("FE")]
    assert model and fe
    version = page.evaluate("window.explorer.health.version")
    assert {(r["model"], r["model_file"], r["model_sha256"], r["balloon_version"])
            for r in model} == {("emulator", "emulator.json", sha, version)}
    assert {(r["model"], r["model_file"]) for r in fe} == {("FE", "curves.h5")}
    with page.expect_download() as d:
        page.click("#export-json")
    data = json.loads(open(d.value.path()).read())
    assert data["service"]["emulator"]["sha256"] == sha
    assert data["service"]["version"] == version
