"""A request field given twice is refused with its location, not read as its last value
(service/repeated_fields.py): Python's json and FastAPI's query parsing both kept the
last one, so ``{"L_mm": 5, "L_mm": 50}`` was answered for L = 50 mm with status 200."""

from __future__ import annotations

import json

import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for

from service.app import create_app
from service.repeated_fields import repeated_body_field

JSON = {"content-type": "application/json"}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    app = create_app(settings_for(tmp_path_factory.mktemp("repeated")))
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


def _post(client, path: str, text: str):
    return client.post(path, content=text.encode(), headers=JSON)


def test_a_design_length_given_twice_is_refused_at_its_field(client):
    r = _post(client, "/v1/predict", '{"design": {"L_mm": 5, "L_mm": 50}, '
                                     '"pressures_pa": [500], "model": "paper"}')
    body = assert_problem(r, 422)
    assert body["errors"][0]["loc"] == ["body", "design", "L_mm"]
    assert body["errors"][0]["field"] == "design.L_mm"
    assert "more than once" in body["errors"][0]["message"]
    assert body["errors"][0]["allowed"] == "each field once per JSON object"


def test_a_top_level_field_given_twice_is_refused(client):
    r = _post(client, "/v1/predict", '{"pressures_pa": [500], "model": "paper", '
                                     '"pressures_pa": [900]}')
    assert assert_problem(r, 422)["errors"][0]["loc"] == ["body", "pressures_pa"]


def test_a_measured_rows_column_given_twice_is_located_in_its_row(client):
    row = ('{"curve_id": "c1", "L_mm": 7.1, "t_mm": 0.5, "pressure_pa": 500, '
           '"angle_deg": 5, "angle_deg": 50}')
    r = _post(client, "/v1/calibrate", '{"rows": [{"curve_id": "c1", "L_mm": 7.1, '
              '"t_mm": 0.5, "pressure_pa": 400, "angle_deg": 4}, ' + row + "]}")
    assert assert_problem(r, 422)["errors"][0]["loc"] == ["body", "rows", 1, "angle_deg"]


def test_the_same_request_without_the_repeat_is_answered(client):
    r = client.post("/v1/predict", json={"design": {"L_mm": 5}, "pressures_pa": [500],
                                         "model": "paper"})
    assert r.status_code == 200, r.text


def test_a_single_valued_query_parameter_given_twice_is_refused(client):
    body = assert_problem(client.get("/v1/curves?limit=2&limit=300"), 422)
    assert body["errors"][0]["loc"] == ["query", "limit"]
    assert "2 times" in body["errors"][0]["message"]


def test_a_list_query_parameter_repeats_as_designed(client):
    r = client.get("/v1/predict/plot?model=paper&measured_pressure_pa=100"
                   "&measured_pressure_pa=200&measured_angle_deg=1&measured_angle_deg=2")
    assert r.status_code == 200, r.text


def test_the_explorer_page_keeps_its_own_address_parameters(client):
    assert client.get("/?L_mm=3&L_mm=4").status_code == 200


@pytest.mark.parametrize("text, loc", [
    ('{"a": 1, "b": {"c": [1, {"d": 2, "d": 3}]}}', ("body", "b", "c", 1, "d")),
    ('[{"x": 1}, {"x": 1, "y": 2, "x": 1}]', ("body", 1, "x")),
    ('{"a": 1, "a": 1}', ("body", "a")),
    ('{"a": {"a": 1}, "b": [{"a": 1}]}', None),
    ("not json", None),
    ("[" * 100_000, None),
])
def test_the_first_repeat_is_located_depth_first(text, loc):
    assert repeated_body_field(text.encode()) == loc
    if loc is None and text.startswith("{"):
        json.loads(text)  # a valid document without repeats
