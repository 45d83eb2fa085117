"""HEAD is GET without the body (RFC 9110 9.3.2; service/middleware.py): a monitor that
probes the service with HEAD got 405 from every FastAPI GET route (found by the
thirtieth session's hostile-input probe)."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for

from service.app import create_app


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    app = create_app(settings_for(tmp_path_factory.mktemp("head")), load_surrogate=False)
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


@pytest.mark.parametrize("path", ["/v1/health", "/v1/materials", "/v1/effects",
                                  "/openapi.json", "/"])
def test_head_answers_as_get_without_the_body(client, path):
    get = client.get(path)
    head = client.head(path)
    assert get.status_code == head.status_code == 200
    assert head.content == b""
    assert head.headers["content-type"] == get.headers["content-type"]
    if "content-length" in get.headers:
        assert head.headers["content-length"] == get.headers["content-length"]


def test_head_of_an_error_is_its_status_and_headers_without_the_problem(client):
    head = client.head("/v1/curves/zz")
    get = client.get("/v1/curves/zz")
    assert head.status_code == get.status_code
    assert head.content == b""
    assert head.headers["content-type"] == get.headers["content-type"]


def test_a_path_without_get_still_refuses_head(client):
    """POST-only operations: HEAD is GET there, which they do not take (405, Allow)."""
    head = client.head("/v1/predict")
    assert head.status_code == 405 and head.content == b""
    assert "POST" in head.headers["allow"]
    assert_problem(client.get("/v1/predict"), 405)
