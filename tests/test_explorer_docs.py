"""/docs (Swagger UI) and /redoc render the API's operations from the vendored assets, in
real headless Chromium, with no request to any host but the server."""

from __future__ import annotations

import httpx
import pytest
from explorer_browser import LiveServer, Watched, screenshot

pytestmark = pytest.mark.timeout(300)  # a browser that hangs fails the test

@pytest.fixture(scope="module")
def server(tmp_path_factory):
    with LiveServer(tmp_path_factory.mktemp("explorer-docs")) as live:
        yield live



def operations(server) -> list[tuple[str, str]]:
    spec = httpx.get(server.url + "/openapi.json").json()
    return [(method.upper(), path) for path, item in spec["paths"].items() for method in item]


def test_swagger_ui_renders_every_operation_offline(browser, server):
    w = Watched(browser, server.url)
    try:
        page = w.page
        page.goto(server.url + "/docs", wait_until="domcontentloaded")
        page.wait_for_selector(".opblock")
        ops = operations(server)
        assert page.locator(".opblock").count() == len(ops)
        shown = {(b.locator(".opblock-summary-method").inner_text().strip(),
                  b.locator(".opblock-summary-path").get_attribute("data-path"))
                 for b in page.locator(".opblock").all()}
        assert shown == set(ops)
        assert ("POST", "/v1/predict") in shown
        # pages for people are not API operations
        assert ("GET", "/") not in set(ops) and ("GET", "/docs") not in set(ops)
        screenshot(page, "docs-swagger-1280")
        assert w.foreign_requests() == [], w.foreign_requests()
        assert w.errors == [], w.errors
    finally:
        w.close()


def test_redoc_renders_the_operations_offline(browser, server):
    w = Watched(browser, server.url)
    try:
        page = w.page
        page.goto(server.url + "/redoc", wait_until="domcontentloaded")
        page.wait_for_selector("[data-section-id^='operation/']")
        assert page.locator("[data-section-id^='operation/']").count() == len(operations(server))
        assert "Angle against pressure" in page.inner_text("body")
        screenshot(page, "docs-redoc-1280")
        assert w.foreign_requests() == [], w.foreign_requests()
        assert w.errors == [], w.errors
    finally:
        w.close()


def test_the_assets_are_served_from_the_package_with_their_licences(server):
    for path in ("/static/vendor/swagger-ui/swagger-ui-bundle.js",
                 "/static/vendor/swagger-ui/swagger-ui.css", "/static/vendor/swagger-ui/LICENSE",
                 "/static/vendor/redoc/redoc.standalone.js", "/static/vendor/redoc/LICENSE",
                 "/static/explorer/js/app.js", "/static/explorer/style.css"):
        r = httpx.get(server.url + path)
        assert r.status_code == 200, path
    html = httpx.get(server.url + "/docs").text + httpx.get(server.url + "/redoc").text
    html += httpx.get(server.url + "/").text
    assert "cdn." not in html and "googleapis" not in html
    missing = httpx.get(server.url + "/static/nope.js")
    assert missing.status_code == 404
    assert missing.headers["content-type"] == "application/problem+json"
