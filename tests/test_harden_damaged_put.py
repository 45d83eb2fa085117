"""No put seals over a damaged record: a publish from an unsealed file (older code,
another tool) reads every record back first and refuses when one does not (the file
unchanged); the service's finished solve is then parked, not lost, and its job says why
and what to run (`balloon db salvage`); once the salvaged file is in place, the next
solve writes the parked result."""

from __future__ import annotations

import os

import pytest
from fastapi.testclient import TestClient
from service_fakes import fast_solve, settings_for
from test_service_jobs import KEY, SOLVE, wait_for
from test_store import record_for
from test_store_links_and_salvage import damage_curve, write_database

from service.app import create_app
from service.cli import main
from solver.precompute.parking import parked_files
from solver.store import CurveStore, DamagedStoreError

STATES = ("finished", "parked", "failed", "cancelled", "timed_out")


def test_a_put_into_an_unsealed_file_refuses_to_seal_over_a_damaged_record(tmp_path):
    path = tmp_path / "c.h5"
    records = write_database(path, sealed=False)
    damage_curve(path, records[1])
    before = path.read_bytes()
    with CurveStore(path, mode="a") as db, pytest.raises(DamagedStoreError) as exc:
        db.put(record_for(L_mm=6.1))
    assert exc.value.records == (records[1].key,)
    assert "balloon db salvage" in str(exc.value)
    assert path.read_bytes() == before      # not sealed over, nothing added


def test_the_services_solve_is_parked_and_the_job_names_salvage(tmp_path, capsys):
    path = tmp_path / "c.h5"
    records = write_database(path, sealed=False)
    damage_curve(path, records[1])
    before = path.read_bytes()
    app = create_app(settings_for(tmp_path, db_path=path), solve_fn=fast_solve,
                     load_surrogate=False)
    with TestClient(app, raise_server_exceptions=False) as client:
        first = client.post("/v1/solve", json=SOLVE, headers=KEY).json()
        job = wait_for(client, first["id"], STATES)
        assert job["status"] == "parked", job
        assert f"record {records[1].key[:12]} of the curve database c.h5 is damaged" \
            in job["error"], job["error"]
        assert "balloon db salvage c.h5 -o NEW.h5" in job["error"]
        assert str(tmp_path) not in job["error"]
        assert job["curve_status"] == "complete"
        assert path.read_bytes() == before                   # the damage not sealed over
        assert [p.stem for p in parked_files(path)] == [first["key"]]

        # the way out the job names: salvage, the new file in place of the old one
        assert main(["db", "salvage", str(path), "-o", str(tmp_path / "new.h5")]) == 0
        capsys.readouterr()
        os.replace(tmp_path / "new.h5", path)
        design = {**SOLVE, "design": {"L_mm": 8.1, "t_mm": 0.6}}
        second = client.post("/v1/solve", json=design, headers=KEY).json()
        assert wait_for(client, second["id"], STATES)["status"] == "finished"
    with CurveStore(path) as db:
        assert {first["key"], second["key"]} <= set(db.keys())
        assert records[1].key not in db and db.damaged_records() == {}
    assert parked_files(path) == []
