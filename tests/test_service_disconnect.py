"""A long request stops soon after its client disconnects: POST /v1/calibrate and POST
/v1/inverse run in a worker thread that the route stops (a ``threading.Event`` the loop
checks at every fit, cross-validation or batch of designs) when the connection closes.

A real server (uvicorn on a loopback port, in a thread) and a real disconnect (the
client's socket closed after the request is sent). The work is slowed by a spy around
its loop's units (each fit and cross-validation, each screen of designs: 0.4 s more),
which records when each unit starts: after the disconnect no unit starts later than
``BOUND_S``; the former code ran every unit to the end (units still started 2.6 s
after the disconnect, when the watch ended)."""

from __future__ import annotations

import json
import socket
import threading
import time

import pytest
from explorer_browser import free_port
from service_fakes import settings_for

from service.app import create_app
from service.disconnect import POLL_S
from service.routes.calibration import EXAMPLE_ROWS

UNIT_S = 0.4                      # each unit of the work made this much slower, s
BOUND_S = POLL_S + UNIT_S + 0.6   # the route notices, the unit running ends; a margin
WATCH_S = 3.0                     # how long after the disconnect nothing may start, s


@pytest.fixture
def server(tmp_path):
    import uvicorn

    app = create_app(settings_for(tmp_path), load_surrogate=False)
    port = free_port()
    srv = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port,
                                        log_level="warning", timeout_graceful_shutdown=2))
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 30
    while not srv.started:
        assert time.monotonic() < deadline and thread.is_alive(), "no server"
        time.sleep(0.05)
    yield port
    srv.should_exit = True
    thread.join(timeout=30)


def slowed(monkeypatch, module, *names: str) -> list[float]:
    """Wrap each ``module.name`` so that a call takes UNIT_S more; their start times."""
    starts: list[float] = []

    def spy_of(real):
        def spy(*args, **kwargs):
            starts.append(time.monotonic())
            time.sleep(UNIT_S)
            return real(*args, **kwargs)
        return spy

    for name in names:
        monkeypatch.setattr(module, name, spy_of(getattr(module, name)))
    return starts


def send_and_leave(port: int, path: str, body: dict, after_s: float) -> float:
    """POST ``body`` and close the connection after ``after_s`` without reading the
    answer; the time of the disconnect."""
    data = json.dumps(body).encode()
    head = (f"POST {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
            f"Content-Length: {len(data)}\r\n\r\n").encode()
    with socket.create_connection(("127.0.0.1", port)) as sock:
        sock.sendall(head + data)
        time.sleep(after_s)
        left = time.monotonic()
    return left


def assert_stopped(starts: list[float], left: float, what: str) -> None:
    time.sleep(WATCH_S)
    assert starts and starts[0] < left, f"the {what} had not started before the disconnect"
    late = [round(t - left, 2) for t in starts if t > left + BOUND_S]
    assert not late, (f"the {what} went on after its client left: units started "
                      f"{late} s after the disconnect (bound {BOUND_S:.2f} s)")


def test_a_calibration_stops_soon_after_its_client_disconnects(server, monkeypatch):
    import surrogate.calibration._loop as loop

    starts = slowed(monkeypatch, loop, "fit", "cross_validate")
    left = send_and_leave(server, "/v1/calibrate", {"rows": EXAMPLE_ROWS, "model": "paper"},
                          after_s=2 * UNIT_S)
    assert_stopped(starts, left, "calibration")


def test_a_design_search_stops_soon_after_its_client_disconnects(server, monkeypatch):
    import surrogate.search.design_search as search

    starts = slowed(monkeypatch, search, "screen")
    body = {"model": "paper", "target": {"kind": "angle_at_pressure", "pressure_pa": 1500,
                                         "angle_deg": 45}}
    left = send_and_leave(server, "/v1/inverse", body, after_s=2 * UNIT_S)
    assert_stopped(starts, left, "design search")
