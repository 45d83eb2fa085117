"""The precompute job with the real FE solver on a tiny mesh (SolverSettings(mesh_level=0,
element="hex1", max_angle_deg=10), a few seconds per design): the CLI end to end, and a
job killed with SIGKILL then resumed -- nothing lost, nothing solved twice."""

import csv
import io
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from solver.store import CurveStore

HERE = Path(__file__).resolve().parent
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), str(HERE.parent)])}
TINY = '\n[settings]\nmesh_level = 0\nelement = "hex1"\nmax_angle_deg = 10\n'
CLI = """
import sys
import service.cli as cli
cli.COMMAND_MODULES = ("service.commands.precompute", "service.commands.db")
if __name__ == "__main__":
    sys.exit(cli.main())
"""



@pytest.fixture
def balloon(monkeypatch):
    """``balloon ARGS`` in-process, through service.cli.main with these two commands."""
    import service.cli as cli

    monkeypatch.setattr(cli, "COMMAND_MODULES", ("service.commands.precompute",
                                                 "service.commands.db"))
    return cli.main


def write_grid(tmp_path, lengths):
    path = tmp_path / "grid.toml"
    path.write_text(f'pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = {lengths}\n'
                    f't_mm = 0.5\n{TINY}')
    return path


def test_cli_end_to_end_with_the_real_solver(tmp_path, balloon, capsys):
    grid, db = write_grid(tmp_path, "[7.1]"), tmp_path / "curves.h5"
    assert balloon(["precompute", str(grid), "--db", str(db), "--no-progress"]) == 0
    assert "1 complete" in capsys.readouterr().err
    with CurveStore(db) as store:
        (record,) = store.records()
        assert store.metadata["generator_command"] == (
            f"balloon precompute {grid} --db {db} --workers 1")
    curve = record.curve
    # the run stops at the first step past max_angle_deg = 10 (the grid's setting)
    assert curve.status == "complete" and curve.angle_deg[-1] >= 10.0
    assert curve.angle_deg[-2] < 10.0 and curve.pressure_pa[-1] > 0.0
    assert record.provenance["wall_time_s"] > 0.0 and "git_commit" in record.provenance

    assert balloon(["db", "export", str(db), "--format", "csv", "-o", str(tmp_path / "c.csv")
                    ]) == 0
    rows = list(csv.DictReader(io.StringIO((tmp_path / "c.csv").read_text())))
    assert len(rows) == len(curve)
    assert float(rows[-1]["angle_deg"]) == curve.angle_deg[-1]  # repr round-trips exactly
    assert rows[0]["key"] == record.key and rows[0]["body_material"] == "pdms_1_10"
    assert float(rows[0]["chamber_offset_mm"]) == record.design.chamber_offset_mm
    assert balloon(["db", "export", str(db), "--format", "json", "--status", "complete",
                    "-o", str(tmp_path / "c.json")]) == 0
    (exported,) = json.loads((tmp_path / "c.json").read_text())
    assert exported["key"] == record.key and exported["settings"]["max_angle_deg"] == 10.0
    assert exported["curve"]["angle_deg"] == curve.angle_deg.tolist()
    assert exported["provenance"]["status"] == "complete"
    assert balloon(["db", "export", str(db), "--status", "failed", "--format", "json"]) == 0
    assert json.loads(capsys.readouterr().out) == []
    assert balloon(["db", "show", str(db), record.key[:6], "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert shown["curve"]["force_mn"][0] is None  # NaN (free tip) exported as null
    assert balloon(["db", "ls", str(db)]) == 0
    assert record.key[:12] in capsys.readouterr().out

    # user mistakes: one line on stderr, exit 2, nothing solved
    bad = tmp_path / "bad.toml"
    bad.write_text(grid.read_text().replace("t_mm = 0.5", "t_mm = -0.5"))
    assert balloon(["precompute", str(bad), "--db", str(db)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("balloon: error: ") and "line 3: t_mm" in err and "0.05 <=" in err
    assert balloon(["db", "show", str(db), "ffff"]) == 2
    capsys.readouterr()
    assert balloon(["precompute", str(grid), "--db", str(tmp_path / "no" / "c.h5")]) == 2
    assert "--db: directory" in capsys.readouterr().err
    assert balloon(["precompute", str(grid), "--db", str(tmp_path)]) == 2
    assert "is not a file" in capsys.readouterr().err
    assert balloon(["db", "ls", str(tmp_path / "missing.h5")]) == 2
    assert "no curve database" in capsys.readouterr().err


def test_killed_job_resumes_without_loss_or_duplicates(tmp_path):
    grid, db = write_grid(tmp_path, "[4.1, 5.1]"), tmp_path / "curves.h5"
    runner = tmp_path / "balloon.py"
    runner.write_text(textwrap.dedent(CLI))
    command = [sys.executable, str(runner), "precompute", str(grid), "--db", str(db),
               "--workers", "1", "--no-progress"]
    job = subprocess.Popen(command, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           start_new_session=True)
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline:
        if db.exists():
            with CurveStore(db) as store:
                if len(store) >= 1:
                    break
        time.sleep(0.2)
    os.killpg(job.pid, signal.SIGKILL)  # the job and its worker, mid-solve
    job.wait(timeout=30)
    with CurveStore(db) as store:  # still a valid file
        before = {r.key: r for r in store.records()}
    assert len(before) == 1  # killed while the worker solved the second design
    assert all(r.curve.status == "complete" for r in before.values())

    rerun = subprocess.run(command, env=ENV, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    assert f"already in the database: {len(before)} done" in rerun.stderr
    assert "solved 1 of 1" in rerun.stderr
    with CurveStore(db) as store:
        after = {r.key: r for r in store.records()}
        runs = store.metadata["runs"]
    assert len(after) == 2 and set(before) <= set(after)
    for key, record in before.items():  # kept as they were, not solved again
        assert after[key].provenance == record.provenance
    assert "finished_utc" not in runs[0] and runs[1]["solved"] == 1
    assert not list(tmp_path.glob(".curves.h5.tmp-*"))


def test_cli_skips_stored_failures_and_retries_them_with_retry_failed(tmp_path, balloon,
                                                                      capsys):
    from solver.precompute import load_grid
    from solver.store import failed_curve, make_record

    grid, db = write_grid(tmp_path, "[7.1]"), tmp_path / "curves.h5"
    (point,) = load_grid(grid).points
    with CurveStore(db, mode="a") as store:  # as a failed solve of an earlier run left it
        store.put(make_record(point.design, point.settings,
                              failed_curve("ConvergenceError: seeded by the test")))
    assert balloon(["precompute", str(grid), "--db", str(db), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "already in the database: 0 done, 1 failed (skipped)" in err
    assert "solved 0 of 0" in err
    with CurveStore(db) as store:
        assert store.get(point.key).curve.reason == "ConvergenceError: seeded by the test"

    assert balloon(["precompute", str(grid), "--db", str(db), "--no-progress",
                    "--retry-failed"]) == 0
    assert "solved 1 of 1" in capsys.readouterr().err
    with CurveStore(db) as store:
        assert store.keys() == [point.key]  # replaced, not duplicated
        assert store.get(point.key).curve.status == "complete"
        assert store.metadata["generator_command"].endswith("--workers 1 --retry-failed")
