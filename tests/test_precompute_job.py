"""The precompute job's logic with a fast deterministic fake solve (tests/
test_precompute_fakes.py): skipping, failures, retries, interruption, worker errors, and
the same code path on a process pool and on a Dask cluster."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from test_precompute_fakes import always_ok_solve, fake_curve, fake_solve

from solver.precompute import load_grid, parse_grid, plan, precompute, run_job
from solver.precompute.job import solve_point
from solver.store import CurveStore

HERE = Path(__file__).resolve().parent
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), str(HERE.parent)])}

# 3 lengths x T in {1, 2, 3}: T = 2 makes fake_solve return a failed curve, T = 3 raise
GRID = """
pairs = [["pdms_1_10", "ecoflex_00_30"]]
L_mm = [4.1, 7.1, 11.1]
t_mm = 0.5
T_mm = [1.0, 2.0, 3.0]
[settings]
mesh_level = 0
element = "hex1"
"""


@pytest.fixture
def grid():
    return parse_grid(GRID, "grid.toml")


def test_plan_skips_done_and_failed_unless_retried(grid):
    keys = [p.key for p in grid.points]
    statuses = {keys[0]: "complete", keys[1]: "stopped", keys[2]: "failed"}
    todo, summary = plan(grid.points, statuses)
    assert [p.key for p in todo] == keys[3:]
    assert (summary.grid_total, summary.skipped_done, summary.skipped_failed,
            summary.to_solve) == (9, 2, 1, 6)
    todo, summary = plan(grid.points, statuses, retry_failed=True)
    assert [p.key for p in todo] == keys[2:] and summary.skipped_failed == 0


def test_solve_point_turns_exceptions_into_failed_records(grid):
    raising = next(p for p in grid.points if p.design.T_mm == 3.0)
    record = solve_point(raising.design, raising.settings, fake_solve)
    assert record.key == raising.key
    assert record.curve.status == "failed" and len(record.curve) == 0
    assert record.curve.reason == "RuntimeError: fake: the solver blew up"
    assert record.provenance["status"] == "failed"


def test_pool_job_stores_everything_then_reruns_solve_only_what_is_missing(grid, tmp_path):
    db_path = tmp_path / "curves.h5"
    summary = precompute(grid, db_path, workers=2, solve_fn=fake_solve, progress=False,
                         command="balloon precompute grid.toml --db curves.h5 --workers 2")
    assert (summary.complete, summary.failed, summary.errors) == (3, 6, 0)
    assert not summary.interrupted and summary.solved == 9
    reasons = {reason for _, _, reason in summary.failures}
    assert reasons == {"fake: Newton did not converge", "RuntimeError: fake: the solver blew up"}
    with CurveStore(db_path) as db:
        assert sorted(db.keys()) == sorted(p.key for p in grid.points)
        ok = db.get(grid.points[0].key)
        assert ok.curve.angle_deg.tolist() == fake_curve(ok.design).angle_deg.tolist()
        meta = db.metadata
    assert meta["generator_command"].startswith("balloon precompute grid.toml")
    assert meta["grid_toml"] == GRID
    assert meta["runs"][0]["solved"] == 9 and "finished_utc" in meta["runs"][0]

    again = precompute(grid, db_path, workers=1, solve_fn=fake_solve, progress=False)
    assert (again.to_solve, again.skipped_done, again.skipped_failed) == (0, 3, 6)

    retried = precompute(grid, db_path, workers=1, solve_fn=always_ok_solve,
                         retry_failed=True, progress=False)
    assert (retried.to_solve, retried.complete) == (6, 6)
    with CurveStore(db_path) as db:
        assert set(db.statuses().values()) == {"complete"} and len(db) == 9
        assert len(db.metadata["runs"]) == 3


def test_one_job_per_database(grid, tmp_path):
    from solver.store import StoreBusyError
    from solver.store.locking import WriterLock

    db_path = tmp_path / "c.h5"
    other_job = WriterLock(tmp_path / "c.h5.job.lock")
    other_job.acquire()
    with pytest.raises(StoreBusyError, match="another precompute job"):
        precompute(grid, db_path, solve_fn=fake_solve, progress=False)
    other_job.release()
    assert not db_path.exists()


class InlineFuture:
    """A finished (or, with done=False, never-finishing) future computed in-process."""

    def __init__(self, fn, args, done=True, error=None):
        self._done, self._error = done, error
        self._value = fn(*args) if done and error is None else None

    def result(self):
        if self._error is not None:
            raise self._error
        return self._value

    def done(self):
        return self._done

    def cancelled(self):
        return False

    def cancel(self):
        return True


class InlineBackend:
    """Submits run at once; ``pending`` futures never finish; ``as_completed`` raises
    KeyboardInterrupt after ``interrupt_after`` results, as Ctrl-C would."""

    def __init__(self, pending=(), interrupt_after=None, broken=()):
        self.pending, self.interrupt_after, self.broken = set(pending), interrupt_after, broken
        self.submitted, self.aborted = 0, None

    def submit(self, fn, *args):
        i, self.submitted = self.submitted, self.submitted + 1
        error = OSError("worker killed (simulated)") if i in self.broken else None
        return InlineFuture(fn, args, done=i not in self.pending, error=error)

    def as_completed(self, futures):
        for i, future in enumerate(list(futures)):
            if i == self.interrupt_after:
                raise KeyboardInterrupt
            if future.done():
                yield future

    def abort(self, futures):
        self.aborted = list(futures)

    def describe(self):
        return "inline"


def test_interrupt_keeps_every_finished_solve_and_aborts_the_rest(grid, tmp_path):
    backend = InlineBackend(pending={4, 5, 7}, interrupt_after=2)
    with CurveStore(tmp_path / "c.h5", mode="a") as db:
        summary = run_job(grid.points, db, backend, fake_solve, progress=False)
        stored = set(db.keys())
    assert summary.interrupted
    # yielded before Ctrl-C: 0, 1; finished but not yet yielded: 2, 3, 6, 8
    assert stored == {grid.points[i].key for i in (0, 1, 2, 3, 6, 8)}
    assert len(backend.aborted) == 3 and summary.not_run == 3
    assert any("interrupted: 3 not run" in line for line in summary.lines())


def test_worker_errors_store_nothing_and_do_not_stop_the_job(grid, tmp_path):
    backend = InlineBackend(broken={1, 4})
    with CurveStore(tmp_path / "c.h5", mode="a") as db:
        summary = run_job(grid.points, db, backend, always_ok_solve, progress=False)
        assert len(db) == 7
    assert (summary.errors, summary.complete) == (2, 7)
    assert all("worker error OSError" in reason for _, _, reason in summary.failures)


def test_dask_local_cluster_runs_the_same_job(grid, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        # through the scheduler's address, as `balloon precompute --scheduler ADDRESS` does
        summary = precompute(grid, tmp_path / "c.h5", scheduler=cluster.scheduler_address,
                             solve_fn=fake_solve, progress=False)
    assert summary.backend.startswith("Dask scheduler") and "(1 workers)" in summary.backend
    assert (summary.complete, summary.failed, summary.errors) == (3, 6, 0)
    with CurveStore(tmp_path / "c.h5") as db:
        record = db.get(grid.points[0].key)
    assert record.curve.angle_deg.tolist() == fake_curve(record.design).angle_deg.tolist()


RUNNER = """
import json, signal, sys
# A shell without job control starts background commands with SIGINT ignored, and the
# child inherits that (a suite run as `pytest ... &` from a script); Ctrl-C in a terminal
# reaches a foreground job with Python's default handler, which is what this test is of.
signal.signal(signal.SIGINT, signal.default_int_handler)
from solver.precompute import load_grid, precompute
from test_precompute_fakes import blocking_fake_solve
if __name__ == "__main__":
    s = precompute(load_grid(sys.argv[1]), sys.argv[2], workers=1,
                   solve_fn=blocking_fake_solve, progress=False)
    print(json.dumps({"interrupted": s.interrupted, "solved": s.solved}), flush=True)
    sys.exit(130 if s.interrupted else 0)
"""


def test_ctrl_c_on_a_running_job_stops_it_and_keeps_what_finished(tmp_path):
    """Deterministic: the third design's solve never returns; Ctrl-C comes once the
    first two are stored and the third has started, whatever the machine's load."""
    grid_path = tmp_path / "grid.toml"
    grid_path.write_text(GRID.replace("T_mm = [1.0, 2.0, 3.0]", "T_mm = 1.0")
                         .replace("[4.1, 7.1, 11.1]", "[4.1, 5.1, 6.1, 7.1, 8.1, 9.1]"))
    runner = tmp_path / "runner.py"
    runner.write_text(textwrap.dedent(RUNNER))
    db_path, marker = tmp_path / "c.h5", tmp_path / "third-started"
    job = subprocess.Popen([sys.executable, str(runner), grid_path, db_path],
                           env={**ENV, "BALLOON_FAKE_MARKER": str(marker)},
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           start_new_session=True)
    deadline = time.monotonic() + 300  # a bound for a broken run, not a timing assumption
    while time.monotonic() < deadline and job.poll() is None:
        if marker.exists() and db_path.exists():
            with CurveStore(db_path) as db:
                if len(db) == 2:
                    break
        time.sleep(0.05)
    os.killpg(job.pid, signal.SIGINT)  # what Ctrl-C in a terminal sends
    out, err = job.communicate(timeout=120)
    assert job.returncode == 130, err
    assert json.loads(out) == {"interrupted": True, "solved": 2}
    with CurveStore(db_path) as db:
        assert len(db) == 2 and set(db.statuses().values()) == {"complete"}
    rerun = precompute(load_grid(grid_path), db_path, workers=1, solve_fn=always_ok_solve,
                       progress=False)
    assert rerun.to_solve == 4 and rerun.skipped_done == 2


def test_progress_bar_shows_counts_failures_and_eta_and_the_summary_counts(grid, tmp_path,
                                                                            capsys):
    with CurveStore(tmp_path / "c.h5", mode="a") as db:
        summary = run_job(grid.points, db, InlineBackend(broken={8}), fake_solve,
                          progress=True)
    bar = capsys.readouterr().err.split("\r")[-1]  # tqdm redraws the line; the final state
    # tqdm's format: "desc: pct|bar| n/total [elapsed<remaining, rate, postfix]"
    assert bar.startswith("precompute: 100%") and " 9/9 [" in bar, bar
    assert "<00:00" in bar  # the ETA field
    # point 8 (L = 11.1, T = 3: a raising solve) is lost to a worker error instead
    assert "complete=3, failed=5, worker_errors=1" in bar, bar
    lines = summary.lines()
    assert lines[0] == "grid: 9 designs; already in the database: 0 done, 0 failed (skipped)"
    assert "solved 8 of 9 on inline" in lines[1]
    assert lines[1].endswith("3 complete, 0 stopped, 5 failed")
    assert lines[2] == "1 lost to worker errors (nothing stored; rerun to retry)"
    assert sum(line.startswith("  failed ") for line in lines) == 6  # 5 failed + 1 error


def test_disk_full_mid_job_parks_the_finished_results_and_the_next_run_writes_them(
        grid, tmp_path, monkeypatch):
    import errno

    import solver.store.hdf5

    db_path = tmp_path / "c.h5"
    real_write, writes = solver.store.hdf5._write_file, []

    def write_until_full(path, data):  # the creation and 3 puts fit, the 4th put does not
        writes.append(path)
        if len(writes) > 4:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(path, data)

    monkeypatch.setattr(solver.store.hdf5, "_write_file", write_until_full)
    with CurveStore(db_path, mode="a") as db:  # the job's loop, on an inline pool
        summary = run_job(grid.points, db, InlineBackend(pending={7}), always_ok_solve,
                          progress=False)
    assert summary.write_error and str(db_path) in summary.write_error
    assert "No space left on device" in summary.write_error
    with CurveStore(db_path) as db:
        stored = set(db.keys())
    # 3 puts published, the 4th failed and stopped the job; everything else that had
    # finished (all but the pending point 7) is parked, the database is as after put 3
    assert len(stored) == 3
    parked = sorted(p.stem for p in (tmp_path / "c.h5.parked").glob("*.h5"))
    assert len(parked) == 5 and not set(parked) & stored
    assert summary.parked == 5 and summary.not_run == 1
    assert any("5 finished results parked in" in line for line in summary.lines())

    monkeypatch.setattr(solver.store.hdf5, "_write_file", real_write)  # space again
    rerun = precompute(grid, db_path, workers=1, solve_fn=always_ok_solve, progress=False)
    assert rerun.unparked == 5 and rerun.to_solve == 1 and rerun.complete == 1
    assert rerun.lines()[0] == "wrote 5 results parked by an earlier run"
    assert not (tmp_path / "c.h5.parked").exists()
    with CurveStore(db_path) as db:
        assert len(db) == 9 and set(db.statuses().values()) == {"complete"}
        record = db.get(parked[0])
    assert record.curve.angle_deg.tolist() == fake_curve(record.design).angle_deg.tolist()


FULL_DISK_RUNNER = """
import resource, signal, sys
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG
import solver.precompute.job as job
from test_precompute_fakes import always_ok_solve
job.default_solve = always_ok_solve  # the CLI's solve, replaced by the fast fake
from service.cli import main
if __name__ == "__main__":
    resource.setrlimit(resource.RLIMIT_FSIZE, (int(sys.argv[3]), resource.RLIM_INFINITY))
    sys.exit(main(["precompute", sys.argv[1], "--db", sys.argv[2], "--workers", "1",
                   "--no-progress"]))
"""


def test_balloon_precompute_on_a_full_file_system_says_where_and_why(tmp_path):
    """A real failed write (the file-size limit, as a full disk would): one line naming
    the database and the cause, exit 1, the file intact, finished results parked."""
    grid_text = GRID.replace("T_mm = [1.0, 2.0, 3.0]", "T_mm = 1.0")
    db_path = tmp_path / "c.h5"
    sizes = []
    for lengths in ("[4.1]", "[4.1, 5.1]"):
        precompute(parse_grid(grid_text.replace("[4.1, 7.1, 11.1]", lengths)), db_path,
                   solve_fn=always_ok_solve, progress=False)
        sizes.append(db_path.stat().st_size)
    before = db_path.read_bytes()
    limit = sizes[1] + (sizes[1] - sizes[0]) // 2  # room for the run's metadata only
    grid_path = tmp_path / "grid.toml"
    grid_path.write_text(grid_text.replace("[4.1, 7.1, 11.1]", "[4.1, 5.1, 6.1, 7.1, 8.1]"))
    runner = tmp_path / "runner.py"
    runner.write_text(textwrap.dedent(FULL_DISK_RUNNER))
    job = subprocess.run([sys.executable, "-X", "faulthandler", str(runner), grid_path,
                          db_path, str(limit)], env=ENV, capture_output=True, text=True,
                         timeout=120)
    assert job.returncode == 1, job.stderr
    assert "Traceback" not in job.stderr
    stopped = [ln for ln in job.stderr.splitlines() if ln.startswith("stopped: ")]
    assert len(stopped) == 1 and f"cannot write {db_path}" in stopped[0], job.stderr
    assert "File too large" in stopped[0]
    with CurveStore(db_path) as db:  # intact: the two records of before, readable
        assert len(db) == 2 and db_path.stat().st_size <= limit
    parked = list((tmp_path / "c.h5.parked").glob("*.h5"))
    assert parked and before  # finished results kept beside the database
    rerun = precompute(load_grid(grid_path), db_path, solve_fn=always_ok_solve,
                       progress=False)
    assert rerun.unparked == len(parked) and rerun.skipped_done == 2 + len(parked)
    with CurveStore(db_path) as db:
        assert len(db) == 5


def test_designs_from_another_database_keep_their_tips_and_take_the_grid_settings(
        tmp_path, capsys):
    """``balloon precompute GRID --designs-from OLD.h5``: the database rebuilt on new
    settings (a mesh): every design of OLD with its own tip, the grid's settings on top,
    new keys; the planned run solves exactly those and skips what the target holds."""
    from service.cli import main
    from solver import Design, SolverSettings
    from solver.store import make_record, record_key

    old = tmp_path / "old.h5"
    designs = [Design(L_mm=4.1), Design(L_mm=7.1), Design(L_mm=7.1)]
    # made on the former level 0, rebuilt on the balanced one (the default)
    tips = [SolverSettings(mesh_divisions="former"), SolverSettings(mesh_divisions="former"),
            SolverSettings(tip="blocked", mesh_divisions="former")]
    with CurveStore(old, mode="a") as db:
        db.put_many([make_record(d, s, fake_curve(d)) for d, s in zip(designs, tips)])
    grid = tmp_path / "grid.toml"
    grid.write_text('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n'
                    '[settings]\nmesh_divisions = "balanced"\n')
    new = tmp_path / "new.h5"
    wanted = {record_key(d, SolverSettings(tip=s.tip, mesh_divisions="balanced"))
              for d, s in zip(designs, tips)}
    # one of them already solved in the target: skipped
    d0 = designs[0]
    with CurveStore(new, mode="a") as db:
        db.put(make_record(d0, SolverSettings(mesh_divisions="balanced"), fake_curve(d0)))
    assert main(["precompute", str(grid), "--db", str(new), "--designs-from", str(old),
                 "--dry-run"]) == 0
    out = capsys.readouterr()
    assert "3 designs; in" in out.out and "1 done" in out.out and "would solve 2" in out.out
    assert "mesh_divisions = 'balanced'" in out.err

    from argparse import Namespace

    from service.commands.precompute import _designs_from_grid
    rebuilt, origin = _designs_from_grid(load_grid(grid), Namespace(designs_from=str(old),
                                                                    db=str(new)))
    assert origin["n_records"] == 3 and origin["path"] == str(old)
    assert {p.key for p in rebuilt.points} == wanted
    assert sorted(p.settings.tip for p in rebuilt.points) == ["blocked", "free", "free"]
    assert all(p.settings.mesh_divisions == "balanced" for p in rebuilt.points)
    with CurveStore(old) as db:
        assert not wanted & set(db.keys())       # new settings, new keys


def test_a_run_records_where_its_designs_came_from(tmp_path, grid):
    db_path = tmp_path / "c.h5"
    origin = {"path": "old.h5", "n_records": 9, "runs": [{"command": "balloon precompute x"}]}
    precompute(grid, db_path, solve_fn=always_ok_solve, progress=False,
               metadata={"designs_from": origin})
    with CurveStore(db_path) as db:
        assert db.metadata["designs_from"] == origin
        assert len(db.metadata["runs"]) == 1


def test_designs_from_take_a_setting_the_grid_names_even_at_its_default(tmp_path):
    """A grid that names the default value of a setting moves records solved with another
    value to it (after a change of default, rebuilding on the new default mesh)."""
    from argparse import Namespace

    from service.commands.precompute import _designs_from_grid
    from solver import Design, SolverSettings
    from solver.store import make_record

    old = tmp_path / "old.h5"
    with CurveStore(old, mode="a") as db:
        db.put(make_record(Design(), SolverSettings(element="hex1", tip="blocked"),
                           fake_curve(Design())))
    grid = tmp_path / "grid.toml"
    grid.write_text('pairs = [["pdms_1_10", "ecoflex_00_30"]]\n[settings]\nelement = "hex2"\n')
    rebuilt, _ = _designs_from_grid(load_grid(grid), Namespace(designs_from=str(old),
                                                               db=str(tmp_path / "new.h5")))
    (point,) = rebuilt.points
    assert point.settings.element == "hex2" and point.settings.tip == "blocked"
