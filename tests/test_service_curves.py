"""GET /v1/curves, /v1/curves/{id}, the plot's nearby FE curves, and the job writer,
on a small database written through the CurveStore API (synthetic curves)."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient
from service_fakes import FakeSurrogate, assert_problem, fast_solve, make_curve, settings_for

from service.app import create_app
from service.store_access import ResultWriter
from solver.design import Design, design_from_dict
from solver.settings import SolverSettings
from solver.store import CurveStore, make_record, record_key

SETTINGS = SolverSettings(mesh_level=0, element="hex1")
# (L_mm, t_mm, body, membrane, status)
ROWS = [(4.1, 0.5, "pdms_1_10", "ecoflex_00_30", "complete"),
        (7.1, 0.5, "pdms_1_10", "ecoflex_00_30", "complete"),
        (7.1, 0.75, "pdms_1_10", "ecoflex_00_30", "failed"),
        (11.1, 0.5, "pdms_1_10", "ecoflex_00_30", "complete"),
        (7.1, 0.5, "ecoflex_00_30", "pdms_1_15", "complete")]


def design(L_mm, t_mm, body, membrane):
    return design_from_dict({"L_mm": L_mm, "t_mm": t_mm, "body_material": body,
                             "membrane_material": membrane})


@pytest.fixture
def db_path(tmp_path):
    path = tmp_path / "curves.h5"
    with CurveStore(path, mode="a") as db:
        for L, t, body, membrane, status in ROWS:
            curve = make_curve(6 if status == "complete" else 1, status=status,
                               reason="" if status == "complete" else "Newton failed")
            db.put(make_record(design(L, t, body, membrane), SETTINGS, curve))
    return path


@pytest.fixture
def client(tmp_path, db_path):
    app = create_app(settings_for(tmp_path, db_path=db_path), solve_fn=fast_solve,
                     load_surrogate=False)
    app.state.models.fitted = FakeSurrogate()
    app.state.models.emulator = app.state.models.fitted
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


def test_health_counts_the_records(client):
    assert client.get("/v1/health").json()["database"] == {
        "name": "curves.h5", "present": True, "records": len(ROWS), "error": None}


def test_list_filters_and_pages(client):
    page = client.get("/v1/curves").json()
    assert page["total"] == 5 and page["next_offset"] is None
    first = page["items"][0]
    assert (first["body_material"], first["L_mm"]) == ("ecoflex_00_30", 7.1)  # sorted
    # make_curve(6): pressures 0..5000 Pa, angle = p / 100
    assert first["max_pressure_pa"] == 5000.0 and first["max_angle_deg"] == 50.0
    r = client.get("/v1/curves", params={"t_mm": 0.5, "body_material": "pdms_1_10"}).json()
    assert [i["L_mm"] for i in r["items"]] == [4.1, 7.1, 11.1]
    r = client.get("/v1/curves", params={"status": "failed"}).json()
    assert [(i["L_mm"], i["t_mm"]) for i in r["items"]] == [(7.1, 0.75)]
    r = client.get("/v1/curves", params={"limit": 2, "offset": 2}).json()
    assert len(r["items"]) == 2 and r["next_offset"] == 4 and r["total"] == 5
    h = first["h_mm"]
    assert client.get("/v1/curves", params={"h_mm": h}).json()["total"] == 5
    assert client.get("/v1/curves", params={"h_mm": h + 0.05}).json()["total"] == 0


def test_the_list_follows_every_write_to_the_database(client, db_path):
    """The records' summary rows are read once per version of the file, and a write
    publishes a new version: the next page lists the new record."""
    assert client.get("/v1/curves").json()["total"] == 5
    with CurveStore(db_path, mode="a") as db:
        db.put(make_record(design(9.1, 0.5, "pdms_1_10", "ecoflex_00_30"), SETTINGS,
                           make_curve(6)))
    page = client.get("/v1/curves", params={"body_material": "pdms_1_10"}).json()
    assert page["total"] == 5 and 9.1 in [i["L_mm"] for i in page["items"]]


def test_list_errors(client, tmp_path):
    assert_problem(client.get("/v1/curves", params={"limit": 0}), 422, "limit")
    assert_problem(client.get("/v1/curves", params={"status": "done"}), 422, "status")
    assert_problem(client.get("/v1/curves", params={"L_mm": "long"}), 422, "L_mm")
    empty = create_app(settings_for(tmp_path, db_path=tmp_path / "none.h5"),
                       load_surrogate=False)
    with TestClient(empty) as c:
        assert "BALLOON_DB_PATH" in assert_problem(c.get("/v1/curves"), 503)["detail"]


def test_a_damaged_database_is_503_not_500(client, tmp_path):
    bad = tmp_path / "bad.h5"
    bad.write_bytes(b"not hdf5 at all")
    app = create_app(settings_for(tmp_path, db_path=bad), load_surrogate=False)
    with TestClient(app, raise_server_exceptions=False) as c:
        assert_problem(c.get("/v1/curves"), 503)


def test_get_one_curve(client):
    key = record_key(design(7.1, 0.5, "pdms_1_10", "ecoflex_00_30"), SETTINGS)
    r = client.get(f"/v1/curves/{key}")
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["id"] == key and body["design"]["L_mm"] == 7.1
    assert body["settings"]["element"] == "hex1"
    assert body["curve"]["angle_deg"] == [0, 10, 20, 30, 40, 50]
    assert body["curve"]["force_mn"] == [None] * 6  # NaN (free tip) is sent as null
    assert body["provenance"]["status"] == "complete"
    body = assert_problem(client.get("/v1/curves/" + "f" * 32), 404)
    assert str(client.app.state.settings.db_path) not in body["detail"]  # no local path
    assert_problem(client.get("/v1/curves/NOT-A-KEY"), 404)  # no such record, whatever the text


def test_plot_overlays_nearby_fe_curves(client):
    from service.plotting import nearby_curves

    found = nearby_curves(client.app.state.settings.db_path, Design(L_mm=8.0), 2, 2000.0)
    # nearest two complete curves of the standard family: L = 7.1 then 11.1 (failed skipped)
    # the records are hex1 solves: each label says so (not the default solve)
    assert [label for label, _, _ in found] == ["FE L=7.1 mm, t=0.5 mm (hex1)",
                                                "FE L=11.1 mm, t=0.5 mm (hex1)"]
    assert max(found[0][1]) <= 2100.0
    r = client.get("/v1/predict/plot", params={"L_mm": 8.0, "nearby": 2})
    assert r.status_code == 200 and r.content[:4] == b"\x89PNG"


def test_the_summary_rows_are_read_once_per_file_version(client, db_path, monkeypatch):
    """/v1/curves and the plot's nearby FE curves read the records' summary rows once per
    version of the file (17 s for the shipped database on a slow core: every plot took
    that long), and again after a write."""
    from service.plotting import nearby_curves
    from solver.store.hdf5 import CurveStore as Store

    reads = []
    summaries = Store.summaries
    monkeypatch.setattr(Store, "summaries",
                        lambda self, **f: reads.append(1) or summaries(self, **f))
    path = client.app.state.settings.db_path
    for _ in range(3):
        nearby_curves(path, Design(L_mm=8.0), 2, 2000.0)
        assert client.get("/v1/curves").json()["total"] == 5
    assert len(reads) == 1
    with CurveStore(db_path, mode="a") as db:
        db.put(make_record(design(9.1, 0.5, "pdms_1_10", "ecoflex_00_30"), SETTINGS,
                           make_curve(6)))
    labels = [label for label, _, _ in nearby_curves(path, Design(L_mm=8.0), 2, 2000.0)]
    assert labels == ["FE L=7.1 mm, t=0.5 mm (hex1)", "FE L=9.1 mm, t=0.5 mm (hex1)"]
    assert client.get("/v1/curves").json()["total"] == 6
    assert len(reads) == 2


def test_solve_of_a_stored_design_is_a_conflict(client):
    body = {"design": {"L_mm": 7.1, "t_mm": 0.5},
            "settings": {"mesh_level": 0, "element": "hex1"}}
    r = client.post("/v1/solve", json=body, headers={"X-API-Key": "test-key"})
    problem = assert_problem(r, 409)
    assert problem["curve_id"] == record_key(design(7.1, 0.5, "pdms_1_10", "ecoflex_00_30"),
                                             SETTINGS)


def test_result_writer_adds_a_record_and_keeps_the_others(db_path):
    new = Design(L_mm=9.1, t_mm=0.6)
    key = ResultWriter(db_path)(new, SETTINGS, make_curve(3))
    with CurveStore(db_path) as db:
        assert len(db) == len(ROWS) + 1
        assert key == record_key(new, SETTINGS) and len(db.get(key).curve) == 3


def test_reads_go_on_while_another_writer_holds_the_database(client, db_path):
    """A precompute job holding the single writer lock does not stop the readers, and a
    finished solve waits for the lock instead of failing."""
    import threading

    writer = CurveStore(db_path, mode="a")  # e.g. `balloon precompute` running
    try:
        assert client.get("/v1/curves").json()["total"] == len(ROWS)
        done = []
        thread = threading.Thread(target=lambda: done.append(
            ResultWriter(db_path, busy_wait_s=30)(Design(L_mm=13.1), SETTINGS, make_curve(2))))
        thread.start()
        thread.join(0.5)
        assert not done  # waiting for the lock
    finally:
        writer.close()
    thread.join(30)
    assert done and client.get("/v1/curves").json()["total"] == len(ROWS) + 1
