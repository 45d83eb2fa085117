"""The explorer page and headers with units (docs/measured-data.md, "Headers with units"),
in real headless Chromium: the page sends the file's rows under the file's own headers,
the server reads them exactly as ``balloon calibrate`` reads the file, and the page
draws the data from the report's ``data.columns_read`` (in Pa and degrees), not from a
reading of its own. Before, the page drew a file headed ``Pressure (kPa)`` at no
pressure at all (``r.pressure_pa`` undefined)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from explorer_browser import LiveServer, open_explorer, screenshot

from surrogate.calibration import jsonable, load_observations, observations_from_rows

pytestmark = pytest.mark.timeout(300)  # a browser that hangs fails the test

# a German Excel's CSV of two curves, its pressure in kPa and its angle in radians
LAB_CSV = """curve_id;L_mm;t_mm;body_material;membrane_material;Druck [kPa];theta (rad);t [min]
s1;7,1;0,5;pdms_1_10;ecoflex_00_30;0;0,001;0
s1;7,1;0,5;pdms_1_10;ecoflex_00_30;0,4;0,03;0,05
s1;7,1;0,5;pdms_1_10;ecoflex_00_30;0,8;0,08;0,1
s1;7,1;0,5;pdms_1_10;ecoflex_00_30;1,2;0,2;0,15
s2;7,1;0,5;pdms_1_10;ecoflex_00_30;0;-0,002;0
s2;7,1;0,5;pdms_1_10;ecoflex_00_30;0,4;0,032;0,05
s2;7,1;0,5;pdms_1_10;ecoflex_00_30;0,8;0,085;0,1
s2;7,1;0,5;pdms_1_10;ecoflex_00_30;1,2;0,21;0,15
"""


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with LiveServer(tmp_path_factory.mktemp("explorer-headers")) as live:
        yield live


def test_the_page_sends_what_the_server_reads_as_the_cli_does_and_draws_it_in_pa(
        watched, server, tmp_path):
    path = tmp_path / "lab.csv"
    path.write_text(LAB_CSV, encoding="utf-8")
    cli = load_observations(path)
    page = open_explorer(watched, server.url)
    sent = page.evaluate("""async (text) => {
        const m = await import("/static/explorer/js/csv.js");
        return m.parseCsv(text);
    }""", LAB_CSV)
    http = observations_from_rows(sent)
    assert http.sha256 == cli.sha256 and http.columns_read == cli.columns_read
    assert [r.column for r in cli.columns_read] == ["pressure_pa", "angle_deg", "time_s"]

    def answer(route):   # the report's reading, from the rows the page sent (no loop run)
        rows = route.request.post_data_json["rows"]
        obs = observations_from_rows(rows)
        route.fulfill(status=200, content_type="application/json", body=json.dumps({
            "interpretation": "stub", "model": {"name": "paper"}, "candidates": [],
            "selected_effects": [], "residual_structured_after": False,
            "data": jsonable({"columns_read": [r.as_dict() for r in obs.columns_read]})}))

    page.route("**/v1/calibrate", answer)
    page.set_input_files("#cal-file", str(path))
    page.fill("#cal-model", "paper")
    page.click("#cal-run")
    page.wait_for_selector('#cal-plot g[data-series="data-0"]', timeout=60_000)
    g = page.locator('#cal-plot g[data-series="data-0"]')
    x, y = json.loads(g.get_attribute("data-x")), json.loads(g.get_attribute("data-y"))
    np.testing.assert_allclose(x, cli.pressure_pa, rtol=1e-12)
    np.testing.assert_allclose(y, cli.angle_deg, rtol=1e-12)
    screenshot(page, "s38-calibration-kpa-header")
