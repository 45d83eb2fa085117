"""The stiffness scales the explorer offers are the server's: GET /v1/materials states
each layer's range and the ratio's (solver/design_space.py, the one table the emulator's
box check reads), and the page's fields, their words and their errors say exactly that.
The page said 0.5 - 2 for each layer while the server answered any common factor (both
layers x 3: the pressure axis x 3) within 0.01 - 100 a layer and 0.25 - 4 for the ratio.

The first test is fast (no browser); the others run in headless Chromium on a live
server with the shipped emulator (tests/explorer_browser.py).
"""

from __future__ import annotations

import json

import pytest
from explorer_browser import LiveServer, open_explorer, screenshot, wait_prediction
from fastapi.testclient import TestClient
from service_fakes import settings_for

from service.app import create_app
from solver.design import Design
from solver.design_space import OutOfBoxError, locate, scaled_material


def _answers(s_body: float, s_membrane: float) -> bool:
    """Whether the emulator's box check (every query's) takes the two layers' scales."""
    design = Design(body_material=scaled_material("pdms_1_10", s_body),
                    membrane_material=scaled_material("ecoflex_00_30", s_membrane))
    try:
        locate(design, reduced=True)
    except OutOfBoxError:
        return False
    return True


def test_the_materials_answer_states_the_scales_the_emulator_takes(tmp_path):
    client = TestClient(create_app(settings_for(tmp_path), load_surrogate=False))
    limits = client.get("/v1/materials").json()["stiffness_scale"]
    (lo, hi), (r_lo, r_hi) = limits["layer"], limits["ratio"]
    assert (lo, hi, r_lo, r_hi) == (0.01, 100.0, 0.25, 4.0)
    # each layer to its ends (the other at the same factor: ratio 1), and past them
    assert _answers(lo, lo) and _answers(hi, hi) and _answers(3, 3)
    assert not _answers(0.99 * lo, 0.99 * lo) and not _answers(1.01 * hi, 1.01 * hi)
    # the ratio to its ends, and past them
    assert _answers(r_lo, 1) and _answers(r_hi, 1) and _answers(2 * r_hi, 2)
    assert not _answers(0.99 * r_lo, 1) and not _answers(1.01 * r_hi, 1)
    assert limits["search"] == [0.5, 2.0]


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with LiveServer(tmp_path_factory.mktemp("explorer-scales")) as live:
        yield live


@pytest.mark.timeout(300)
def test_the_page_states_the_servers_stiffness_scales(watched, server):
    page = open_explorer(watched, server.url)
    for name in ("body_scale", "membrane_scale"):
        assert page.inner_text(f"#{name}-range-text") == (
            "0.01 - 100 x preset moduli; body / membrane 0.25 - 4")
        assert page.get_attribute(f"#{name}", "min") == "0.01"
        assert page.get_attribute(f"#{name}", "max") == "100"
        # the slider spans the ratio's range: one layer moved, the other at 1
        assert page.get_attribute(f"#{name}-range", "min") == "0.25"
        assert page.get_attribute(f"#{name}-range", "max") == "4"
    # a common factor outside the former 0.5 - 2 is answered: the pressure axis scaled
    page.fill("#body_scale", "3")
    page.fill("#membrane_scale", "3")
    wait_prediction(page, L_mm=7.1)
    page.wait_for_function("window.explorer.prediction.design.body_material.id.endsWith('x3')"
                           " && window.explorer.prediction.design.membrane_material.id"
                           ".endsWith('x3')")
    assert page.locator("#refused").is_hidden()
    screenshot(page, "s38-both-layers-3x")
    page.fill("#body_scale", "0")
    page.wait_for_selector("#err-body_scale:not([hidden])")
    assert ("allowed: 0.01 to 100 x preset moduli, body / membrane 0.25 to 4"
            in page.inner_text("#err-body_scale"))
    screenshot(page, "s38-scale-zero-refused")


@pytest.mark.timeout(300)
def test_the_pages_scale_limits_come_from_the_server(watched, server):
    page = watched.page

    def other_limits(route):
        body = json.loads(route.fetch().text())
        body["stiffness_scale"] = {"layer": [0.02, 50], "ratio": [0.3, 3], "search": [0.5, 2]}
        route.fulfill(json=body)

    page.route("**/v1/materials", other_limits)
    page = open_explorer(watched, server.url)
    assert page.inner_text("#body_scale-range-text") == (
        "0.02 - 50 x preset moduli; body / membrane 0.3 - 3")
    assert page.get_attribute("#membrane_scale", "max") == "50"
    assert page.get_attribute("#membrane_scale-range", "max") == "3"
