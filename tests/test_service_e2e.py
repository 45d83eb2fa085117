"""End to end: a real FE solve job (tiny mesh) submitted over HTTP, polled with progress,
finished, and its curve stored in the database and served by /v1/curves/{id}.

In the default suite (7 s on a quiet 2-core machine, 16-19 s on a loaded one): the job
mechanics' corner cases are covered by test_service_jobs.py with injected solve
functions, this one shows that the real path works."""

from __future__ import annotations

import time

from fastapi.testclient import TestClient
from service_fakes import settings_for

from service.app import create_app
from solver.store import CurveStore

KEY = {"X-API-Key": "test-key"}
TINY = {"mesh_level": 0, "element": "hex1", "max_angle_deg": 10}


def test_a_real_solve_job_is_stored_and_served(tmp_path):
    db_path = tmp_path / "curves.h5"
    app = create_app(settings_for(tmp_path, db_path=db_path, job_time_limit_s=300),
                     load_surrogate=False)
    with TestClient(app) as client:
        r = client.post("/v1/solve", json={"design": {"L_mm": 7.1, "t_mm": 0.5},
                                           "settings": TINY}, headers=KEY)
        assert r.status_code == 202, r.text
        job_id, steps_seen = r.json()["id"], set()
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline:
            job = client.get(f"/v1/jobs/{job_id}").json()
            steps_seen.add(job["progress"]["step"])
            if job["status"] not in ("queued", "running"):
                break
            time.sleep(0.2)
        assert job["status"] == "finished", job
        assert job["curve_status"] in ("complete", "stopped")
        # the solver stops once |angle| > max_angle_deg = 10
        assert job["progress"]["angle_deg"] > 10 and job["progress"]["pressure_pa"] > 0
        curve = client.get(f"/v1/curves/{job['curve_id']}").json()["curve"]
        assert curve["angle_deg"][0] == 0 and curve["angle_deg"][-1] > 10
        again = client.post("/v1/solve", json={"design": {"L_mm": 7.1, "t_mm": 0.5},
                                               "settings": TINY}, headers=KEY)
        assert again.status_code == 409  # now in the database
    with CurveStore(db_path) as db:
        assert db.keys() == [job["curve_id"]]
