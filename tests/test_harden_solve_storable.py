"""POST /v1/solve is refused before anything is queued when the database cannot take the
finished solve (BALLOON_DB_PATH a directory, a device, a file with a second hard link):
a 503 problem naming the file by its name and saying what is wrong, never its path;
/v1/health names it among its problems. A path with no file yet is still solved: the
first put creates the database there."""

from __future__ import annotations

import os

import pytest
from service_fakes import assert_problem, fast_solve
from test_service_jobs import KEY, SOLVE, make_client, wait_for

from solver.store import CurveStore


def _directory(tmp_path):
    path = tmp_path / "curves.h5"
    path.mkdir()
    return path, "curves.h5 is a directory"


def _device(tmp_path):
    return "/dev/null", "null is not a regular file (a device or a pipe)"


def _hard_link(tmp_path):
    CurveStore(tmp_path / "curves.h5", mode="a").close()
    os.link(tmp_path / "curves.h5", tmp_path / "other.h5")
    return tmp_path / "curves.h5", "curves.h5 has 2 names (hard links)"


@pytest.mark.parametrize("make", [_directory, _device, _hard_link])
def test_a_solve_the_database_cannot_store_is_refused_before_it_is_queued(tmp_path, make):
    db_path, words = make(tmp_path)
    written = []
    with make_client(tmp_path, fast_solve, written,
                     db_path=db_path) as client:
        r = client.post("/v1/solve", json=SOLVE, headers=KEY)
        body = assert_problem(r, 503)
        assert body["type"].endswith(":unavailable")
        assert words in body["detail"] and "BALLOON_DB_PATH" in body["detail"]
        assert str(tmp_path) not in r.text and "/dev" not in r.text
        assert client.get("/v1/health").json()["jobs"]["queued"] == 0
        health = client.get("/v1/health").json()
        assert health["status"] == "degraded"
        assert any(words in p and "POST /v1/solve answers 503" in p
                   for p in health["problems"]), health["problems"]
    assert written == []


def test_a_database_path_with_no_file_yet_is_solved(tmp_path):
    written = []
    with make_client(tmp_path, fast_solve, written,
                     db_path=tmp_path / "new.h5") as client:
        r = client.post("/v1/solve", json=SOLVE, headers=KEY)
        assert r.status_code == 202, r.text
        assert wait_for(client, r.json()["id"])["status"] == "finished"
        health = client.get("/v1/health").json()
        assert not any("POST /v1/solve" in p for p in health["problems"])
    assert len(written) == 1


def test_without_an_api_key_health_does_not_blame_the_database_for_solves(tmp_path):
    # solves are disabled (403) without a key: the database's state is no reason then
    path, _ = _directory(tmp_path)
    with make_client(tmp_path, fast_solve, db_path=path, api_key=None) as client:
        assert client.post("/v1/solve", json=SOLVE, headers=KEY).status_code == 403
        problems = client.get("/v1/health").json()["problems"]
    assert not any("POST /v1/solve" in p for p in problems), problems
