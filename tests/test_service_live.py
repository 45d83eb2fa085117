"""The README's client snippets (docs/snippets/, included verbatim in the README) run
against a real server: the installed `balloon serve` command on 127.0.0.1.

The server uses a surrogate file saved from the paper's preset and a synthetic
database; expected numbers come from the paper's model (Table 4-5 constants).
"""

from __future__ import annotations

import csv
import hashlib
import io
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest
from service_fakes import make_curve

from solver.design import Design
from solver.settings import SolverSettings
from solver.store import CurveStore, make_record
from surrogate import paper_surrogate, save_surrogate

ROOT = Path(__file__).resolve().parents[1]
SNIPPETS = ROOT / "docs" / "snippets"


def balloon() -> list[str]:
    """The installed ``balloon`` command, as the README runs it (else the same CLI's module)."""
    script = Path(sys.executable).parent / "balloon"
    return [str(script)] if script.is_file() else [sys.executable, "-m", "service.cli"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("live")
    save_surrogate(paper_surrogate(), tmp / "surrogate.json")
    with CurveStore(tmp / "curves.h5", mode="a") as db:
        db.put(make_record(Design(), SolverSettings(mesh_level=0), make_curve()))
    port = free_port()
    env = {**os.environ, "BALLOON_DB_PATH": str(tmp / "curves.h5"),
           "BALLOON_SURROGATE_PATH": str(tmp / "surrogate.json"),
           "BALLOON_API_KEY": "live-key", "BALLOON_MODELS_DIR": str(tmp / "models"),
           "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([*balloon(), "serve", "--host", "127.0.0.1",
                             "--port", str(port), "--log-level", "warning"], env=env,
                            cwd=tmp, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    while True:
        try:
            health = httpx.get(f"{url}/v1/health", timeout=1).json()
            break
        except httpx.HTTPError:
            if proc.poll() is not None or time.monotonic() > deadline:
                proc.kill()
                pytest.fail(f"server did not start: {proc.stdout.read().decode()[-2000:]}")
            time.sleep(0.2)
    assert health["surrogate"]["loaded"] and health["surrogate"]["name"] == "paper"
    yield {"url": url, "env": {**env, "BALLOON_URL": url}}
    proc.terminate()
    proc.wait(10)


def run_snippet(server, name: str, interpreter: list[str], args: tuple[str, ...] = (),
                stderr: list | None = None) -> str:
    out = subprocess.run([*interpreter, str(SNIPPETS / name), *args], env=server["env"],
                         capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == 0, out.stderr
    if stderr is not None:
        stderr.append(out.stderr)
    return out.stdout


def test_python_client_snippet(server):
    out = run_snippet(server, "client.py", [sys.executable])
    lines = out.splitlines()
    assert lines[0].split()[:2] == ["500", "Pa"]
    assert "45 deg needs" in out and "#1: L =" in out
    assert lines[-1] == "422 design.t_mm 0.05 <= t_mm <= 5"


def test_batch_snippet(server, tmp_path):
    """A lab's designs ranked by the pressure for 45 deg: every row kept in its place (a
    refused one with the server's words: the field and its range), the model file named
    by its SHA-256 from /v1/health, progress on stderr. The former snippet asked a fixed
    grid, dropped a refused design from the CSV and named no model file."""
    designs = tmp_path / "designs.csv"
    designs.write_text("name,L_mm,t_mm,T_mm\nshort,4.1,0.5,\nlong,15.1,0.5,\n"
                       "outside,3.5,0.5,1.2\ntypo,9,0.7x,\ncomma,9,0,7,1\n")
    err: list[str] = []
    text = run_snippet(server, "batch.py", [sys.executable], (str(designs),), err)
    rows = list(csv.DictReader(io.StringIO(text)))
    assert [r["name"] for r in rows] == ["short", "long", "outside", "typo", "comma"]
    # a longer chamber bends more at a pressure: it needs less for 45 deg (A = a L)
    assert 0 < float(rows[1]["pressure_pa"]) < float(rows[0]["pressure_pa"])
    assert rows[0]["error"] == rows[1]["error"] == ""
    assert rows[2]["pressure_pa"] == "" and "L_mm" in rows[2]["error"]
    assert "4 <= L_mm <= 18" in rows[2]["error"]
    assert rows[3]["error"].startswith("design.t_mm:")
    # "0,7" in a comma-separated file is two cells: not answered as t = 0 and T = 7
    assert rows[4]["pressure_pa"] == "" and "cells do not match the header" in rows[4]["error"]
    health = httpx.get(f"{server['url']}/v1/health", timeout=10).json()
    sha = hashlib.sha256((ROOT / "service" / "data" / "emulator.json").read_bytes()).hexdigest()
    assert health["emulator"]["sha256"] == sha
    assert {(r["model_file"], r["model_sha256"], r["balloon_version"]) for r in rows} == {
        ("emulator.json", sha, health["version"])}
    assert err[0].endswith("5/5 designs\n")


def test_pump_snippet(server):
    lines = run_snippet(server, "pump.py", [sys.executable]).splitlines()
    assert [ln.split()[:2] for ln in lines[:3]] == [["2.0", "s"], ["4.0", "s"], ["8.0", "s"]]
    assert "pump gauge" in lines[0] and lines[3].startswith("45 deg needs ")
    assert lines[3].endswith("s at 2.5 ul/s")


@pytest.mark.skipif(shutil.which("curl") is None, reason="needs curl")
def test_curl_snippets(server):
    import json

    body = json.loads(run_snippet(server, "predict.sh", ["bash"]))
    assert body["pressure_pa"] == [500, 1000, 1500, 2000] and body["model"] == "emulator"
    pump = json.loads(run_snippet(server, "pump.sh", ["bash"]))
    assert pump["time_s"] == [2, 4, 8] and pump["volume_ul"] == [5, 10, 20]
    job, polled = run_snippet(server, "solve.sh", ["bash"]).splitlines()
    assert json.loads(job)["status"] in ("queued", "running")
    assert json.loads(polled)["id"] == json.loads(job)["id"]
    r = httpx.delete(f"{server['url']}/v1/jobs/{json.loads(job)['id']}",
                     headers={"X-API-Key": "live-key"}, timeout=30)
    assert r.status_code in (200, 409)
