"""The explorer's fixes from the forty-ninth session's new-user audit, in real headless
Chromium on one live server (the shipped emulator and database; FE solves faked by
``service_solves.landing_solve`` in real worker processes):

- the design search bounds every length of the box, not L and t alone: a lab with one
  body mould pins T, b and h (one click takes them from the design panel, scaled back to
  W = 3 mm where the search runs), and every design listed has that mould;
- a finished FE solve's plot shows its stored curve, not also the progress dots of steps
  the solver replaced (the overshoot past the 90-deg stop was drawn past the curve's end).

Screenshots: test-artifacts/explorer/s49-*.png.
"""

from __future__ import annotations

import json

import pytest
from explorer_browser import LiveServer, open_explorer, screenshot, solved_refused_design
from service_solves import landing_solve

pytestmark = pytest.mark.timeout(300)

SEARCHED = ("!document.getElementById('inv-table').hidden || document.getElementById("
            "'inv-explanation').textContent.replace('Searching...', '').length > 0")


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with LiveServer(tmp_path_factory.mktemp("explorer-s49"), solve_fn=landing_solve) as live:
        yield live


def test_the_design_search_keeps_the_body_mould_of_the_design_above(watched, server):
    # a 2x copy (W = 6 mm) of T 1.2, b 1.8, h 0.2 mm: the search's box is at W = 3 mm
    page = watched.page
    page.goto(server.url + "/#W_mm=6&L_mm=18&t_mm=1.2&T_mm=2.4&b_mm=3.6&h_mm=0.4&pair=0")
    page.wait_for_selector("body[data-ready=true]")
    assert page.locator("#link-note").is_hidden()    # the link's design taken whole
    page.click("#inv-mould")
    pinned = {k: (page.input_value(f"#inv-{k}-lo"), page.input_value(f"#inv-{k}-hi"))
              for k in "Tbh"}
    assert pinned == {"T": ("1.2", "1.2"), "b": ("1.8", "1.8"), "h": ("0.2", "0.2")}
    page.fill("#inv-pressure", "2000")
    page.fill("#inv-angle", "45")
    page.fill("#inv-n", "3")
    with page.expect_request("**/v1/inverse") as sent:
        page.click("#inv-run")
    body = json.loads(sent.value.post_data)
    assert body["T_bounds_mm"] == [1.2, 1.2] and body["b_bounds_mm"] == [1.8, 1.8]
    assert body["h_bounds_mm"] == [0.2, 0.2] and "L_bounds_mm" not in body
    page.wait_for_function(SEARCHED, timeout=120_000)
    rows = page.evaluate("Array.from(document.querySelectorAll('#inv-table tbody tr'))"
                         ".map((tr) => Array.from(tr.children).map((td) => td.textContent))")
    screenshot(page, "s49-inverse-mould")
    assert len(rows) == 3
    for row in rows:   # rank, pair, scales, L, t, T, b, h, ...
        assert row[5:8] == ["1.200", "1.800", "0.200"], row
        assert 4 <= float(row[3]) <= 18 and 0.5 <= float(row[4]) <= 1.2
    # a bound the box does not hold is named beside its boxes with the box's range
    page.fill("#inv-T-lo", "0.2")
    page.fill("#inv-T-hi", "0.3")
    page.click("#inv-run")
    page.wait_for_selector("#err-inv-T:not([hidden])")
    assert "0.6" in page.inner_text("#err-inv-T") and "2" in page.inner_text("#err-inv-T")
    assert watched.foreign_requests() == []


def test_a_finished_solve_draws_no_step_past_its_stored_curve(watched, server):
    page = solved_refused_design(watched, server.url)
    screenshot(page, "s49-fe-solve-landed")
    stored = json.loads(page.locator('#plot g[data-series="fe-solve"]').get_attribute("data-y"))
    assert max(stored) == 90
    # the replaced 92-deg step is no point of the plot once the stored curve is drawn
    assert page.locator('#plot g[data-series="fe-progress"]').count() == 0
    assert "reaches 90.0 deg" in page.inner_text("#job")


def test_a_refusal_shows_the_command_it_names_as_code_not_with_backticks(watched, server):
    """The server's words name commands in backticks (`balloon solve`): on the CLI a
    reader's convention, on the page they were shown as typed characters."""
    page = open_explorer(watched, server.url)
    page.fill("#L_mm", "3")  # outside the emulator's box (L 4..18 mm): refused
    page.wait_for_selector("#refused:not([hidden])")
    detail = page.locator("#refused-detail")
    assert "`" not in detail.inner_text()
    assert "balloon solve" in detail.locator("code").all_inner_texts()
    assert "L_mm" in detail.inner_text() and "4" in detail.inner_text()
