"""Hostile requests of the thirty-seventh session: refusals that named the field but not
what it takes. A field of fixed words (``status``, ``objective``, ``target.kind``,
``pressures_at``, ``settings.element``), an object sent as something else or left out
(``design``, ``target``, the body), a measured cell that is not a number, missing or an
empty curve id, a curve whose design changes, and a design of no fitted family came back
422 without ``allowed``."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for

from service.app import create_app
from service.routes.calibration import EXAMPLE_ROWS

KEY = {"X-API-Key": "test-key"}


@pytest.fixture
def client(tmp_path):
    app = create_app(settings_for(tmp_path), load_surrogate=False)
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


def _allowed(body: dict, field: str) -> str:
    """The ``allowed`` of the error at ``field`` (the test fails where it has none)."""
    entries = [e for e in body["errors"] if e["field"] == field]
    assert entries, body
    assert entries[0].get("allowed"), entries[0]
    return entries[0]["allowed"]


@pytest.mark.parametrize("method, path, kw, field, words", [
    ("get", "/v1/curves", {"params": {"status": "done"}}, "status", "'complete'"),
    ("post", "/v1/predict", {"json": {"pressures_pa": [500], "pressures_at": "gauge",
                                      "model": "paper"}}, "pressures_at", "'pump_gauge'"),
    ("post", "/v1/inverse", {"json": {"target": {"kind": "angle", "pressure_pa": 1500,
                                                 "angle_deg": 45}, "model": "paper"}},
     "target.kind", "'angle_at_pressure'"),
    ("post", "/v1/inverse", {"json": {"target": {"pressure_pa": 1500, "angle_deg": 45},
                                      "objective": "fast", "model": "paper"}},
     "objective", "'certainty'"),
    ("post", "/v1/solve", {"json": {"settings": {"element": "hex3"}}, "headers": KEY},
     "settings.element", "'hex1'"),
])
def test_a_field_of_fixed_words_states_them(client, method, path, kw, field, words):
    body = assert_problem(getattr(client, method)(path, **kw), 422, field)
    assert words in _allowed(body, field)
    entry = next(e for e in body["errors"] if e["field"] == field)
    assert "is not one of these" in entry["message"], entry


@pytest.mark.parametrize("path, sent, field, names", [
    ("/v1/predict", {"design": "7.1", "pressures_pa": [500], "model": "paper"}, "design",
     ("L_mm", "t_mm", "membrane_material")),
    ("/v1/inverse", {"model": "paper"}, "target", ("kind", "pressure_pa", "angle_deg")),
    ("/v1/inverse/pressure", [1, 2], "body", ("design", "angles_deg")),
])
def test_an_object_sent_as_something_else_or_left_out_states_its_fields(
        client, path, sent, field, names):
    body = assert_problem(client.post(path, json=sent), 422, field)
    allowed = _allowed(body, field)
    assert all(name in allowed for name in names), allowed


def _rows(column: str, value, row: int = 2) -> list[dict]:
    rows = [dict(r) for r in EXAMPLE_ROWS]
    rows[row][column] = value
    return rows


@pytest.mark.parametrize("column, value, allowed", [
    ("pressure_pa", "abc", "pressure_pa <= "),
    ("angle_deg", "NaN", "angle_deg <= 720"),
    ("L_mm", None, "0.5 <= L_mm <= 60"),
    ("time_s", "", "0 <= time_s <= "),
    ("curve_id", None, "non-empty text"),
    ("t_mm", 0.6, "one t_mm in every row of curve 's1'"),
])
def test_a_refused_measured_cell_states_what_it_may_hold(client, column, value, allowed):
    r = client.post("/v1/calibrate", json={"rows": _rows(column, value), "model": "paper"})
    body = assert_problem(r, 422, f"rows.2.{column}")
    assert allowed in _allowed(body, f"rows.2.{column}")


def test_a_design_of_no_fitted_family_states_the_families(client):
    r = client.post("/v1/predict", json={"design": {"b_mm": 1.2}, "pressures_pa": [500],
                                         "model": "paper"})
    body = assert_problem(r, 422, "design")
    assert "pdms_1_10/ecoflex_00_30" in _allowed(body, "design")
    assert body["detail"].count("pdms_1_10/ecoflex_00_30") == 1, body["detail"]  # once


@pytest.mark.parametrize("method, path, kw", [
    ("post", "/v1/predict?model=exponential", {"json": {"pressures_pa": [500],
                                                        "model": "paper"}}),
    ("post", "/v1/calibrate?save=lab1", {"json": {"rows": EXAMPLE_ROWS, "model": "paper"}}),
    ("get", "/v1/health?verbose=1", {}),
    ("get", "/v1/materials?limit=1", {}),
    ("get", "/v1/jobs/" + "0" * 32 + "?wait=1", {}),
])
def test_a_query_string_an_operation_does_not_read_is_refused(client, method, path, kw):
    """It was ignored: POST /v1/predict?model=exponential answered from the body's model."""
    name = path.split("?")[1].split("=")[0]
    body = assert_problem(getattr(client, method)(path, **kw), 422, name)
    assert body["errors"][0]["loc"] == ["query", name]
    assert "no query string" in _allowed(body, name)


def test_operations_with_query_parameters_and_pages_keep_theirs(client):
    assert client.get("/v1/curves?limit=2").status_code in (200, 503)   # no database: 503
    assert "did you mean 'limit'" in client.get("/v1/curves?limt=2").text
    assert client.get("/?L_mm=3").status_code == 200
    assert client.get("/openapi.json?x=1").status_code == 200


@pytest.mark.parametrize("path, sent, field, names", [
    ("/v1/predict", {"pressures_pa": [500], "flow_ul_s": 2.5, "inlet": 5, "model": "paper"},
     "inlet", ("channel_width_mm", "viscosity_pa_s")),
    ("/v1/inverse", {"target": {"pressure_pa": 1500, "angle_deg": 45},
                     "material_pairs": [5], "model": "paper"}, "material_pairs.0",
     ("body_material", "membrane_material")),
])
def test_an_object_field_is_not_told_the_range_of_a_namesake(client, path, sent, field,
                                                              names):
    """The body's ``inlet`` was told "true or false" (the plot's query parameter of that
    name); an item of ``material_pairs`` its list's "1-20 values"."""
    body = assert_problem(client.post(path, json=sent), 422, field)
    allowed = _allowed(body, field)
    assert all(name in allowed for name in names), allowed
    assert "true or false" not in allowed and "values" not in allowed, allowed


def _calibrate(tmp_path, rows, **limits):
    app = create_app(settings_for(tmp_path, **limits), load_surrogate=False)
    with TestClient(app, raise_server_exceptions=False) as c:
        return c.post("/v1/calibrate", json={"rows": rows, "model": "paper", "folds": 2})


def test_more_curves_than_the_server_calibrates_are_refused_before_the_work(tmp_path):
    """20,000 rows of 5,000 curves (the schema's limits) kept a worker busy past 5 min."""
    rows = EXAMPLE_ROWS + [dict(r, curve_id="s3") for r in EXAMPLE_ROWS[:5]]
    body = assert_problem(_calibrate(tmp_path, rows, max_calibration_curves=2), 422, "rows")
    assert "3 curves" in body["detail"] and "BALLOON_MAX_CALIBRATION_CURVES" in body["detail"]
    assert _allowed(body, "rows").startswith("at most 2 curves per request")


def test_more_designs_than_the_server_calibrates_are_refused_before_the_work(tmp_path):
    rows = [dict(r, L_mm=9.1) if r["curve_id"] == "s2" else r for r in EXAMPLE_ROWS]
    body = assert_problem(_calibrate(tmp_path, rows, max_calibration_designs=1), 422, "rows")
    assert "2 nominal designs" in body["detail"]
    assert _allowed(body, "rows").startswith("at most 1 nominal designs per request")


def test_data_within_the_limits_are_calibrated(tmp_path):
    r = _calibrate(tmp_path, EXAMPLE_ROWS, max_calibration_curves=2, max_calibration_designs=1)
    assert r.status_code == 200, r.text


def test_a_force_target_on_a_model_without_force_is_refused_at_its_kind(client):
    """It was 200 "not reachable by any design ... widen the bounds" after 128 designs."""
    r = client.post("/v1/inverse", json={"target": {"kind": "force_at_pressure",
                                                    "pressure_pa": 1500, "force_mn": 1},
                                         "model": "paper"})
    body = assert_problem(r, 422, "target.kind")
    assert "gives no blocked-tip force" in body["detail"]
    assert "angle_at_pressure" in _allowed(body, "target.kind")
