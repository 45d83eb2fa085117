"""A finished FE solve job is never lost when the database cannot be written (disk full,
read-only file system): the result is parked beside the database (as the precompute job
does), the job says "parked" and why (naming the database by its name only),
/v1/health says so, and the next write that succeeds writes it first."""

from __future__ import annotations

import errno

from fastapi.testclient import TestClient
from service_fakes import fast_solve, settings_for
from test_service_jobs import KEY, SOLVE, wait_for

from service.app import create_app
from solver.precompute.parking import parked_files
from solver.store import CurveStore


def test_a_solve_the_database_cannot_take_is_parked_and_written_later(tmp_path,
                                                                       monkeypatch):
    db_path = tmp_path / "curves.h5"
    app = create_app(settings_for(tmp_path, db_path=db_path), solve_fn=fast_solve,
                     load_surrogate=False)

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    states = ("finished", "parked", "failed", "cancelled", "timed_out")
    with TestClient(app, raise_server_exceptions=False) as client:
        monkeypatch.setattr("solver.store.hdf5._write_file", full)
        first = client.post("/v1/solve", json=SOLVE, headers=KEY).json()
        job = wait_for(client, first["id"], states)
        assert job["status"] == "parked", job
        assert "curves.h5 cannot be written" in job["error"]
        assert "No space left on device" in job["error"] and str(tmp_path) not in job["error"]
        assert job["curve_status"] == "complete"
        assert [p.stem for p in parked_files(db_path)] == [first["key"]]
        health = client.get("/v1/health").json()
        assert health["status"] == "degraded"
        assert any("1 finished solve result(s) parked" in p for p in health["problems"])

        monkeypatch.undo()  # the disk has room again: the next write takes both
        design = {**SOLVE, "design": {"L_mm": 8.1, "t_mm": 0.6}}
        second = client.post("/v1/solve", json=design, headers=KEY).json()
        job = wait_for(client, second["id"], states)
        assert job["status"] == "finished", job
        with CurveStore(db_path) as db:
            assert {first["key"], second["key"]} <= set(db.keys())
        assert parked_files(db_path) == []
        assert client.get(f"/v1/curves/{first['key']}").status_code == 200
        health = client.get("/v1/health").json()
        assert not any("parked" in p for p in health["problems"])


def test_a_solve_nothing_can_take_is_named_lost_without_a_local_path(tmp_path, monkeypatch):
    # the database and every parking directory refuse (a full disk): the job's error
    # named the database by its full path (the store's StoreWriteError)
    db_path = tmp_path / "curves.h5"
    app = create_app(settings_for(tmp_path, db_path=db_path), solve_fn=fast_solve,
                     load_surrogate=False)

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    with TestClient(app, raise_server_exceptions=False) as client:
        monkeypatch.setattr("solver.store.hdf5._write_file", full)
        monkeypatch.setattr("solver.precompute.parking.park", full)
        first = client.post("/v1/solve", json=SOLVE, headers=KEY).json()
        job = wait_for(client, first["id"], ("finished", "parked", "failed"))
    assert job["status"] == "failed", job
    assert "curves.h5" in job["error"] and "No space left on device" in job["error"]
    assert "lost" in job["error"] and str(tmp_path) not in job["error"], job["error"]
