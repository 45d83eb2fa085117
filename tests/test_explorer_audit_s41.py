"""The explorer's fixes from the forty-first session's syringe-pump audit, in real headless
Chromium on one live server (the shipped emulator and database): the time axis of a
narrow screen is labelled with its ticks' own values, the flow rate takes what the API
takes (its limits from the server's schema), and the legend lists only what is drawn.
Screenshots: test-artifacts/explorer/s41-*.png.
"""

from __future__ import annotations

import pytest
from explorer_browser import LiveServer, Watched, change, open_explorer, screenshot

pytestmark = pytest.mark.timeout(300)

# the x axis's tick labels (the plot's labels group, centred under each tick)
X_TICKS = ("Array.from(document.querySelectorAll('#plot text[text-anchor=middle]'))"
           ".filter((t) => t.parentNode.getAttribute('fill') === '#374151')"
           ".map((t) => [t.textContent, Number(t.getAttribute('x'))])")


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with LiveServer(tmp_path_factory.mktemp("explorer-s41")) as live:
        yield live


def switched(watched, server, ready: str, select: str, value: str, done: str):
    """The explorer once ``ready`` holds, with ``select`` set to ``value`` and ``done``
    holding after it (JavaScript conditions)."""
    page = open_explorer(watched, server.url)
    page.wait_for_function(ready)
    page.select_option(select, value)
    page.wait_for_function(done)
    return page


def test_a_narrow_time_axis_labels_each_tick_with_its_own_value(browser, server):
    # at 400 px the plot takes four ticks: 0-10 s in steps of 2.5 s, labelled 0 3 5 8 10
    narrow = Watched(browser, server.url, width=400)
    try:
        page = narrow.page
        page.goto(server.url + "/#ask=time_s&max=10&flow=2.5")
        page.wait_for_selector("body[data-ready=true]")
        page.wait_for_function("window.explorer.prediction"
                               " && window.explorer.prediction.asked === 'times_s'")
        ticks = page.evaluate(X_TICKS)
        screenshot(page, "s41-narrow-time-axis")
        assert narrow.errors == [] and narrow.foreign_requests() == []
    finally:
        narrow.close()
    labels = [float(text) for text, _ in ticks]
    assert labels[0] == 0 and labels[-1] == 10 and len(labels) >= 3
    # each label is the value at its place: evenly spaced ticks, evenly spaced values
    xs = [x for _, x in ticks]
    for (text, x) in ticks:
        assert float(text) == pytest.approx(10 * (x - xs[0]) / (xs[-1] - xs[0]), abs=1e-9)


def test_the_flow_rate_takes_the_apis_range(watched, server):
    # the page refused 0.001 ul/s ("allowed: from 0.01 to 1000"), which POST /v1/predict
    # takes (1e-06 <= flow_ul_s <= 1000); its own comment said the schema set it
    page = switched(watched, server, "document.getElementById('flow').min === '0.000001'",
                    "#ask_axis", "time_s", "window.explorer.prediction"
                    " && window.explorer.prediction.asked === 'times_s'")
    change(page, "#flow", "0.001")
    page.wait_for_function("window.explorer.prediction"
                           " && window.explorer.prediction.flow_ul_s === 0.001")
    assert page.is_hidden("#err-flow_ul_s")
    change(page, "#flow", "0")
    page.wait_for_selector("#err-flow_ul_s:not([hidden])")
    error = page.inner_text("#err-flow_ul_s")
    assert "from 0.000001 to 1000 ul/s" in error
    # a pump's rate stepped by the keyboard moves by a whole step, from the value shown
    change(page, "#flow", "2.5")
    page.focus("#flow")
    page.keyboard.press("ArrowUp")
    assert page.input_value("#flow") == "3.5"
    screenshot(page, "s41-flow-range")
    assert watched.errors == [] and watched.foreign_requests() == []


def test_the_force_view_lists_only_curves_it_draws(watched, server):
    # by force the legend listed the three nearest free-tip FE curves, whose force is
    # null: three entries with no line
    page = switched(watched, server,
                    "document.querySelectorAll('#plot g[data-series^=fe-]').length > 0",
                    "#y_axis", "force",
                    "document.getElementById('curve-h').textContent.includes('force')"
                    " && document.querySelector('#plot g[data-series=prediction]')")
    series = page.evaluate("Array.from(document.querySelectorAll('#plot g[data-series]'))"
                           ".map((g) => [g.dataset.series, g.querySelectorAll('path').length])")
    screenshot(page, "s41-force-legend")
    assert series and all(drawn > 0 for _, drawn in series), series
    assert watched.errors == [] and watched.foreign_requests() == []


def test_a_tubing_length_and_bore_both_in_error_are_both_named(watched, server):
    # with the tubing's length in error the bore's error was hidden until the length was
    # mended (the pump audit of the forty-first session); both are named at once
    page = switched(watched, server, "document.body.dataset.ready === 'true'",
                    "#ask_axis", "time_s", "window.explorer.prediction"
                    " && window.explorer.prediction.asked === 'times_s'")
    page.check("#inlet")
    change(page, "#tubing_length", "-5")
    change(page, "#tubing_bore", "0")
    page.wait_for_selector("#err-tubing_length:not([hidden])")
    page.wait_for_selector("#err-tubing_bore:not([hidden])")
    assert "0.05" in page.inner_text("#err-tubing_bore")
    change(page, "#tubing_length", "0")          # no tubing: its bore does not count
    page.wait_for_selector("#err-tubing_bore", state="hidden")
    assert watched.errors == [] and watched.foreign_requests() == []
