"""Solve jobs: submitted, polled, finished, cancelled, timed out, failed; a full queue.

The solve functions are fakes (tests/service_fakes.py) run in real worker processes;
the end-to-end test with the real FE solver is in test_service_e2e.py.
"""

from __future__ import annotations

import time

import pytest
from fastapi.testclient import TestClient
from service_fakes import (
    assert_problem,
    crashing_solve,
    failing_solve,
    fast_solve,
    settings_for,
    slow_solve,
)

from service.app import create_app
from service.jobs import JobManager
from solver.design import Design
from solver.errors import NotFoundError
from solver.settings import MAX_MESH_LEVEL, SolverSettings

KEY = {"X-API-Key": "test-key"}
SOLVE = {"design": {"L_mm": 9.1, "t_mm": 0.6},
         "settings": {"mesh_level": 0, "element": "hex1", "max_angle_deg": 10}}


def wait_for(client, job_id: str, states=("finished", "failed", "cancelled", "timed_out"),
             timeout_s: float = 60.0) -> dict:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        job = client.get(f"/v1/jobs/{job_id}").json()
        if job["status"] in states:
            return job
        time.sleep(0.05)
    raise AssertionError(f"job {job_id} still {job['status']} after {timeout_s} s")


def make_client(tmp_path, solve_fn, written=None, **overrides):
    written = [] if written is None else written

    def write(design, settings, curve):
        written.append((design, settings, curve))
        return "c" * 32

    app = create_app(settings_for(tmp_path, **overrides), solve_fn=solve_fn, write_fn=write,
                     load_surrogate=False)
    return TestClient(app, raise_server_exceptions=False)


def test_a_job_is_submitted_polled_and_finished(tmp_path):
    written = []
    with make_client(tmp_path, fast_solve, written) as client:
        r = client.post("/v1/solve", json=SOLVE, headers=KEY)
        assert r.status_code == 202, r.text
        job = r.json()
        assert r.headers["location"] == f"/v1/jobs/{job['id']}"
        assert job["status"] in ("queued", "running")
        assert job["design"]["L_mm"] == 9.1 and job["settings"]["element"] == "hex1"
        done = wait_for(client, job["id"])
    assert done["status"] == "finished", done
    assert done["progress"] == {"step": 3, "pressure_pa": 300.0, "volume_ul": 0.75,
                                "angle_deg": 3.0, "newton_iterations": 4,
                                "cutbacks": None}    # the fake solve reports none
    assert done["curve_id"] == "c" * 32 and done["curve_status"] == "complete"
    assert done["started_utc"] and done["finished_utc"]
    (design, settings, curve), = written  # exactly one write, through the writer
    assert design.L_mm == 9.1 and settings.mesh_level == 0 and len(curve) == 4


def test_the_same_design_while_active_returns_the_same_job(tmp_path):
    with make_client(tmp_path, slow_solve) as client:
        first = client.post("/v1/solve", json=SOLVE, headers=KEY).json()
        second = client.post("/v1/solve", json=SOLVE, headers=KEY).json()
        assert first["id"] == second["id"]
        client.delete(f"/v1/jobs/{first['id']}", headers=KEY)


def test_cancel_a_running_job_and_then_again(tmp_path):
    with make_client(tmp_path, slow_solve) as client:
        job = client.post("/v1/solve", json=SOLVE, headers=KEY).json()
        running = wait_for(client, job["id"], states=("running",))
        deadline = time.monotonic() + 30
        while running["progress"]["step"] < 1 and time.monotonic() < deadline:
            running = client.get(f"/v1/jobs/{job['id']}").json()
        assert running["progress"]["pressure_pa"] == 50.0
        r = client.delete(f"/v1/jobs/{job['id']}", headers=KEY)
        assert r.status_code == 200 and r.json()["status"] == "cancelled"
        assert_problem(client.delete(f"/v1/jobs/{job['id']}", headers=KEY), 409)


def test_a_full_queue_is_answered_503_with_retry_after(tmp_path):
    designs = [{**SOLVE, "design": {"L_mm": 5.0 + i, "t_mm": 0.6}} for i in range(4)]
    with make_client(tmp_path, slow_solve, queue_size=2, retry_after_s=7) as client:
        ids = [client.post("/v1/solve", json=designs[0], headers=KEY).json()["id"]]
        wait_for(client, ids[0], states=("running",))  # the one worker is busy
        ids += [client.post("/v1/solve", json=d, headers=KEY).json()["id"]
                for d in designs[1:3]]               # two wait: the queue is full
        r = client.post("/v1/solve", json=designs[3], headers=KEY)
        body = assert_problem(r, 503)
        assert r.headers["retry-after"] == "7" and "queue is full" in body["detail"]
        # cancelling a queued job frees its place at once
        assert client.delete(f"/v1/jobs/{ids[2]}", headers=KEY).json()["status"] == "cancelled"
        assert client.post("/v1/solve", json=designs[3], headers=KEY).status_code == 202
        health = client.get("/v1/health").json()["jobs"]
        assert health["running"] == 1 and health["queued"] == 2


def test_a_job_over_the_time_limit_is_stopped(tmp_path):
    with make_client(tmp_path, slow_solve, job_time_limit_s=1.0) as client:
        job = client.post("/v1/solve", json=SOLVE, headers=KEY).json()
        done = wait_for(client, job["id"])
    assert done["status"] == "timed_out" and "time limit" in done["error"]


@pytest.mark.parametrize("solve_fn, message", [
    (failing_solve, "refused by the fake solver"),
    (crashing_solve, "exit code 3"),
])
def test_failed_and_crashed_solves_are_reported(tmp_path, solve_fn, message):
    written = []
    with make_client(tmp_path, solve_fn, written) as client:
        job = client.post("/v1/solve", json=SOLVE, headers=KEY).json()
        done = wait_for(client, job["id"])
        assert client.get("/v1/health").status_code == 200  # the server is unharmed
    assert done["status"] == "failed" and message in done["error"]
    assert written == []


def test_solve_and_job_errors(tmp_path):
    with make_client(tmp_path, fast_solve) as client:
        r = client.post("/v1/solve", json={"settings": {"mesh_level": 9}}, headers=KEY)
        problem = assert_problem(r, 422, "settings.mesh_level")
        assert f"0 <= mesh_level <= {MAX_MESH_LEVEL}" in problem["errors"][0]["allowed"]
        r = client.post("/v1/solve", json={"settings": {"tip": "spring"}}, headers=KEY)
        assert_problem(r, 422, "settings.spring_k_n_per_m")  # a spring needs a stiffness
        assert_problem(client.get("/v1/jobs/" + "a" * 32), 404)
        assert_problem(client.get("/v1/jobs/nope"), 404)  # an id that cannot exist: not found


def test_manager_write_failure_keeps_the_error(tmp_path):
    def broken_writer(design, settings, curve):
        raise OSError("disk full")

    jobs = JobManager(fast_solve, broken_writer, workers=1, queue_size=1)
    jobs.start()
    try:
        job = jobs.submit(Design(), SolverSettings(), "k")
        deadline = time.monotonic() + 60
        while jobs.get(job.id).active and time.monotonic() < deadline:
            time.sleep(0.05)
        done = jobs.get(job.id)
        assert done.status == "failed" and "disk full" in done.error
        with pytest.raises(NotFoundError):
            jobs.get("missing")
    finally:
        jobs.shutdown()


def test_queue_size_zero_still_feeds_idle_workers(tmp_path):
    with make_client(tmp_path, slow_solve, queue_size=0) as client:
        first = client.post("/v1/solve", json=SOLVE, headers=KEY)
        assert first.status_code == 202  # the idle worker takes it
        wait_for(client, first.json()["id"], states=("running",))
        other = {**SOLVE, "design": {"L_mm": 5.0, "t_mm": 0.6}}
        assert_problem(client.post("/v1/solve", json=other, headers=KEY), 503)
        client.delete(f"/v1/jobs/{first.json()['id']}", headers=KEY)
