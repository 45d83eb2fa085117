"""What a hostile audit sends: strict JSON numbers, deep JSON, bad ids, a damaged
database, and what an unauthenticated answer may not show (local paths)."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient
from service_fakes import FakeSurrogate, assert_problem, fast_solve, settings_for
from test_store import record_for

from service.app import create_app
from solver.store import CurveStore

DESIGN = {"L_mm": 7.1, "t_mm": 0.5}


def make_client(tmp_path, **overrides):
    app = create_app(settings_for(tmp_path, **overrides), solve_fn=fast_solve,
                     write_fn=lambda d, s, c: "k" * 32, load_surrogate=False)
    app.state.models.fitted = FakeSurrogate()
    app.state.models.emulator = app.state.models.fitted
    return TestClient(app, raise_server_exceptions=False)


@pytest.fixture
def client(tmp_path):
    with make_client(tmp_path) as c:
        yield c


KEY = {"X-API-Key": "test-key"}


@pytest.mark.parametrize("value", [True, "7.1", [7.1], {"v": 7.1}])
def test_numbers_are_strict_json_numbers(client, value):
    r = client.post("/v1/predict", json={"design": {"L_mm": value}, "pressures_pa": [1000]})
    assert_problem(r, 422, "design.L_mm")
    r = client.post("/v1/solve", headers=KEY, json={"design": {"L_mm": value}})
    assert_problem(r, 422, "design.L_mm")  # `L_mm: true` must never queue a 1 mm solve
    r = client.post("/v1/predict", json={"design": DESIGN, "pressures_pa": [value]})
    assert_problem(r, 422)


def test_integers_are_numbers_but_not_the_other_way_round(client):
    r = client.post("/v1/predict", json={"design": {"L_mm": 7, "t_mm": 1}, "pressures_pa": [0]})
    assert r.status_code == 200 and r.json()["design"]["L_mm"] == 7.0
    r = client.post("/v1/solve", headers=KEY, json={"settings": {"mesh_level": 0.5}})
    assert_problem(r, 422, "settings.mesh_level")
    r = client.post("/v1/solve", headers=KEY, json={"settings": {"mesh_level": True}})
    assert_problem(r, 422, "settings.mesh_level")


@pytest.mark.parametrize("depth", [5_000, 30_000])
def test_deep_json_is_422(client, depth):
    body = "[" * depth + "]" * depth
    r = client.post("/v1/predict", content=body, headers={"content-type": "application/json"})
    assert_problem(r, 422, "body")
    r = client.post("/v1/predict", content=b'{"pressures_pa": [1], "x": "\xff"}',
                    headers={"content-type": "application/json"})
    assert_problem(r, 422)


def test_calibrate_refuses_unknown_fields_and_huge_numbers_naming_row_and_column(client):
    from service.routes.calibration import EXAMPLE_ROWS

    r = client.post("/v1/calibrate", json={"rows": EXAMPLE_ROWS, "model": "paper",
                                           "sav": "typo"})
    assert_problem(r, 422, "sav")
    rows = [dict(row) for row in EXAMPLE_ROWS]
    rows[3]["pressure_pa"] = 10 ** 400
    r = client.post("/v1/calibrate", json={"rows": rows, "model": "paper"})
    body = assert_problem(r, 422, "rows.3.pressure_pa")
    assert "(401 characters) does not fit a 64-bit float" in body["detail"]  # as written
    for bad in (True, [1.0], {"a": 1}):
        rows[3]["pressure_pa"] = bad
        assert_problem(client.post("/v1/calibrate", json={"rows": rows, "model": "paper"}),
                       422, "rows.3.pressure_pa")


@pytest.mark.parametrize("job_id", ["nope", "0" * 32, "Z" * 40, "0" * 31])
def test_an_unknown_job_is_404_whatever_its_id_looks_like(client, job_id):
    assert_problem(client.get(f"/v1/jobs/{job_id}"), 404)
    assert_problem(client.delete(f"/v1/jobs/{job_id}", headers=KEY), 404)


def test_unauthenticated_answers_show_no_local_paths(tmp_path, client):
    secret = str(tmp_path)
    health = client.get("/v1/health")
    assert health.status_code == 200 and secret not in health.text
    assert health.json()["database"]["name"] == "curves.h5"
    assert health.json()["surrogate"]["file"] == "none.json"
    with CurveStore(tmp_path / "curves.h5", mode="a") as db:
        db.put(record_for(L_mm=7.1))
    for r in (client.get("/v1/curves/" + "f" * 32), client.get("/v1/health"),
              client.get("/v1/curves"),
              client.post("/v1/predict", json={"pressures_pa": [0], "model": "nope"})):
        assert secret not in r.text, r.text


def test_no_surrogate_file_is_degraded_health_without_its_path(tmp_path):
    app = create_app(settings_for(tmp_path))  # surrogate_path does not exist
    with TestClient(app) as c:
        r = c.get("/v1/health")
    body = r.json()
    assert r.status_code == 200 and body["status"] == "degraded"
    assert any("no fitted surrogate" in p for p in body["problems"])
    assert "none.json" in body["surrogate"]["error"] and str(tmp_path) not in r.text


def damaged_database(path, damage="header"):
    """A database whose records index is damaged (flipped bytes in its object header),
    the same unsealed (as older code wrote it), or a file of older code on which HDF5
    loops for ever (test_store_damage.LOOP)."""
    from test_store_damage import LOOP, flip_object_header, unseal

    if damage == "loop":
        path.write_bytes(LOOP.read_bytes())
        return
    with CurveStore(path, mode="a") as db:
        db.put_many([record_for(L_mm=L) for L in (4.1, 5.1, 7.1, 9.1)])
    data = path.read_bytes()
    path.write_bytes(flip_object_header(unseal(data) if damage == "unsealed" else data, 1))


@pytest.mark.parametrize("damage", ["header", "unsealed", "loop"])
def test_a_damaged_database_is_503_and_degraded_health(tmp_path, monkeypatch, damage):
    from solver.store import integrity

    monkeypatch.setattr(integrity, "STALL_S", 3.0)
    damaged_database(tmp_path / "curves.h5", damage)
    with make_client(tmp_path) as c:
        for r in (c.get("/v1/curves"), c.get("/v1/curves/" + "0" * 32)):
            body = assert_problem(r, 503)
            assert "curves.h5 is damaged" in body["detail"] and str(tmp_path) not in r.text
        r = c.get("/v1/health")
        body = r.json()
        assert r.status_code == 200 and body["status"] == "degraded", body
        assert "damaged" in body["database"]["error"] and body["database"]["records"] is None
        assert any("damaged" in p for p in body["problems"]) and str(tmp_path) not in r.text
        plot = c.get("/v1/predict/plot", params={"L_mm": 7.1})  # nearby FE curves: none
        assert plot.status_code in (200, 503)


def test_predict_provenance_names_the_database_not_its_path(client):
    class Fitted(FakeSurrogate):
        def predict(self, design, pressures_pa, level=0.95):
            p = super().predict(design, pressures_pa, level)
            p.provenance = {"database_path": "/home/someone/private/curves.h5",
                            "git_commit": "abc"}
            return p

    client.app.state.models.fitted = Fitted()
    client.app.state.models.emulator = client.app.state.models.fitted
    r = client.post("/v1/predict", json={"design": DESIGN, "pressures_pa": [500]})
    assert r.status_code == 200 and "/home/someone" not in r.text
    assert r.json()["provenance"] == {"database": "curves.h5", "git_commit": "abc"}
