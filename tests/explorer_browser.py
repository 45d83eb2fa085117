"""Shared fixtures of the explorer's browser tests: a real server on a free loopback
port (uvicorn in a thread, the shipped surrogate, a copy of the shipped database, fake
FE solves from service_solves.py in real worker processes) and headless Debian Chromium
driven by Playwright. Without /usr/bin/chromium or playwright the tests skip, saying why
(.ci/run installs both).

Screenshots go to test-artifacts/explorer/ (git-ignored). tests/conftest.py registers
the fixtures ``browser`` and ``watched`` (``browser_fixture``, ``watched_fixture``) for
every module; a browser test module defines its own ``server`` fixture.
"""

from __future__ import annotations

import shutil
import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from urllib.parse import urlsplit

import pytest

from service.settings import ServiceSettings

ROOT = Path(__file__).resolve().parent.parent
CHROMIUM = Path("/usr/bin/chromium")
ARTIFACTS = ROOT / "test-artifacts" / "explorer"
API_KEY = "test-key"
# Chromium as root on a closed network: no sandbox, no background connections.
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                 "--no-first-run", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def running(server) -> Iterator[None]:
    """A ``uvicorn.Server`` run in a thread while the block runs (started when it enters)."""
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 30
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("the test server did not start")
        time.sleep(0.05)
    try:
        yield
    finally:
        server.should_exit = True
        thread.join(timeout=30)


class LiveServer:
    """The app served by uvicorn in a thread; ``url`` is http://127.0.0.1:PORT."""

    def __init__(self, tmp: Path, solve_fn=None) -> None:
        import uvicorn

        from service.app import create_app

        db = tmp / "curves.h5"
        shutil.copy(ROOT / "service" / "data" / "curves.h5", db)
        settings = ServiceSettings(db_path=db,
                                   surrogate_path=ROOT / "service" / "data" / "surrogate.json",
                                   models_dir=tmp / "models", api_key=API_KEY, job_time_limit_s=60)
        self.settings = settings
        self.app = create_app(settings, solve_fn=solve_fn)
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        # the module's browser may still hold keep-alive connections when the server is
        # torn down (fixtures end in reverse order): without a limit uvicorn waits for
        # them, and the join below timed out after 30 s in every browser module
        self.server = uvicorn.Server(uvicorn.Config(self.app, host="127.0.0.1", port=self.port,
                                                    log_level="warning",
                                                    timeout_graceful_shutdown=2))
        self.thread = threading.Thread(target=self.server.run, daemon=True)

    def __enter__(self) -> LiveServer:
        self.thread.start()
        deadline = time.monotonic() + 30
        while not self.server.started:
            if time.monotonic() > deadline or not self.thread.is_alive():
                raise RuntimeError("the test server did not start")
            time.sleep(0.05)
        return self

    def __exit__(self, *exc) -> None:
        self.server.should_exit = True
        self.thread.join(timeout=30)


def launch_browser():
    """(playwright, browser), or pytest.skip with the reason."""
    if not CHROMIUM.is_file():
        pytest.skip("no /usr/bin/chromium (apt-get install -y chromium; .ci/run does it)")
    sync_api = pytest.importorskip(
        "playwright.sync_api", reason="playwright (Python) is not installed: pip install '.[test]'")
    pw = sync_api.sync_playwright().start()
    browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
    return pw, browser


class Watched:
    """A page with every request and every console error recorded."""

    def __init__(self, browser, server_url: str, width: int = 1280) -> None:
        self.context = browser.new_context(viewport={"width": width, "height": 900},
                                           accept_downloads=True)
        # generous: on a loaded 2-core machine Chromium took 60 s to evaluate Swagger UI's
        # 1.7 MB bundle (2 s when quiet); a real failure still fails, only later
        self.context.set_default_timeout(120_000)
        self.page = self.context.new_page()
        self.requests: list[str] = []
        self.errors: list[str] = []
        self.server = urlsplit(server_url).netloc
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(f"page error: {e}"))

    def foreign_requests(self) -> list[str]:
        """Requests to any host but the server (data: and blob: URLs have no host)."""
        out = []
        for url in self.requests:
            parts = urlsplit(url)
            if parts.scheme in ("data", "blob", "about"):
                continue
            if parts.netloc != self.server:
                out.append(url)
        return out

    def close(self) -> None:
        self.context.close()


@pytest.fixture(scope="module", name="browser")
def browser_fixture():
    """One headless Chromium per test module."""
    pw, chromium = launch_browser()
    yield chromium
    chromium.close()
    pw.stop()


@pytest.fixture(name="watched")
def watched_fixture(browser, server):
    """A fresh page (own context) on the module's ``server`` fixture, watched."""
    w = Watched(browser, server.url)
    yield w
    w.close()


def screenshot(page, name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    page.screenshot(path=str(path), full_page=True)
    return path


def open_explorer(watched: Watched, url: str):
    page = watched.page
    page.goto(url + "/")
    page.wait_for_selector("body[data-ready=true]")
    return page


def solved_refused_design(watched: Watched, url: str):
    """The explorer with L = 3 mm (outside the emulator's box: refused) solved by the
    server's FE solve function, its stored curve drawn."""
    page = open_explorer(watched, url)
    page.fill("#L_mm", "3")
    page.wait_for_selector("#refused:not([hidden])")
    page.fill("#api_key", API_KEY)
    page.click("#solve")
    page.wait_for_function("document.getElementById('job').dataset.status === 'finished'",
                           timeout=60_000)
    page.wait_for_selector('#plot g[data-series="fe-solve"]')
    return page


def wait_prediction(page, **design):
    """Wait until the prediction shown is of a design with these values (to 1e-9)."""
    cond = " && ".join(f"Math.abs(p.design.{k} - {v}) < 1e-9" for k, v in design.items())
    page.wait_for_function(
        f"(() => {{ const p = window.explorer.prediction; return p && {cond}; }})()")


def change(page, selector, value):
    """Type ``value`` into a field and commit it (the change event)."""
    page.fill(selector, str(value))
    page.dispatch_event(selector, "change")


def hold_predict(page, wanted=lambda body: True) -> list:
    """Route POST /v1/predict so that the first request whose JSON body ``wanted`` accepts
    is held (the test answers it later with ``continue_()``); the others pass. The list
    of held routes fills when that request is sent."""
    held: list = []

    def route(r):
        if not held and wanted(r.request.post_data_json):
            held.append(r)
        else:
            r.continue_()

    page.route("**/v1/predict", route)
    return held


def wait_held(page, held: list, what: str):
    """The held route of ``hold_predict`` once its request is sent (up to ~20 s)."""
    for _ in range(1000):
        if held:
            return held[0]
        page.wait_for_timeout(20)
    raise AssertionError(f"{what} was never asked")


def release(route) -> None:
    """Answer a held request, unless the page has already given it up (aborted)."""
    try:
        route.continue_()
    except Exception:  # the browser no longer waits for it
        pass
