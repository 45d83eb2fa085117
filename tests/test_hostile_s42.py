"""The forty-second session's hostile-input audit (round two after tests/test_hostile_s41.py):
a compressed body, truthy words for a query's bool, locks an interrupted command left
behind, a FIFO where a file goes, a user's stop angle the FE landed beside, and what a
fresh probe of every route and command found.

Each test failed on the code before its fix (commit messages say which).
"""

from __future__ import annotations

import gzip

import pytest
from fastapi.testclient import TestClient
from service_fakes import PROBLEM, assert_problem, settings_for

from service.app import create_app


@pytest.fixture
def client(tmp_path):
    """The app over fakes (no model loaded): the HTTP plumbing, not the physics."""
    with TestClient(create_app(settings_for(tmp_path), load_surrogate=False)) as c:
        yield c


@pytest.mark.parametrize("coding", ["gzip", "deflate", "br", "gzip, identity"])
def test_a_compressed_body_is_a_415_naming_what_is_taken(client, coding):
    """A gzip-encoded body was read as JSON and refused 422 "cannot be parsed as JSON",
    which never said why. It is a 415 with ``Accept-Encoding: identity`` (RFC 9110
    15.5.16), never decoded (a decompression bomb would expand past the body limit)."""
    body = gzip.compress(b'{"design": {}, "pressures_pa": [1000]}')
    r = client.post("/v1/predict", content=body, headers={
        "Content-Type": "application/json", "Content-Encoding": coding})
    problem = assert_problem(r, 415, "Content-Encoding")
    assert r.headers["accept-encoding"] == "identity"
    assert problem["errors"][0]["allowed"] == "identity"
    assert "uncompressed" in problem["detail"]
    spec = client.get("/openapi.json").json()
    assert "415" in spec["paths"]["/v1/predict"]["post"]["responses"]


def test_an_identity_coding_or_a_bodyless_request_passes(client):
    """``Content-Encoding: identity`` is no coding; a GET with the header has no body."""
    r = client.post("/v1/predict", content=b'{"pressures_pa": [true]}', headers={
        "Content-Type": "application/json", "Content-Encoding": "identity"})
    assert_problem(r, 422, "pressures_pa.0")
    assert client.get("/v1/health", headers={"Content-Encoding": "gzip"}).status_code == 200


@pytest.mark.parametrize("word", ["yes", "on", "1", "0", "True", "off", "f", ""])
def test_a_query_bool_is_true_or_false_as_json_spells_them(client, word):
    """``/v1/predict/plot?inlet=yes`` (or on, 1, True, off, f) was read as a bool in
    pydantic's lax mode. A query's bool is spelt as a JSON body's is: exactly ``true`` or
    ``false``; anything else is a 422 naming the field and those two words."""
    r = client.get("/v1/predict/plot", params={"inlet": word, "flow_ul_s": 2.5,
                                               "model": "paper"})
    problem = assert_problem(r, 422, "inlet")
    (error,) = problem["errors"]
    assert error["allowed"] == "true or false" and repr(word) in error["message"], error
    assert r.headers["content-type"] == PROBLEM


@pytest.mark.parametrize("word", ["true", "false"])
def test_a_query_bool_takes_true_and_false(client, word):
    """Taken: the request reaches the model (the paper's, which answers by pressure only,
    refuses the flow rate: the plot's time axis)."""
    r = client.get("/v1/predict/plot", params={"inlet": word, "flow_ul_s": 2.5,
                                               "model": "paper"})
    assert [e["field"] for e in assert_problem(r, 422)["errors"]] == ["flow_ul_s"]
