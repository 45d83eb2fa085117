"""The precompute job where its database or its process meets trouble: a database named
through a symbolic link, a second job, another writer holding the lock, a damaged
record, and the job killed with SIGKILL while its workers solve."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from test_precompute_fakes import always_ok_solve, fake_curve
from test_precompute_job import ENV, GRID, InlineBackend
from test_store_links_and_salvage import damage_curve

from service.cli import main
from solver.precompute import JobSummary, load_grid, parse_grid, precompute, run_job
from solver.store import (
    CurveStore,
    DamagedStoreError,
    StoreBusyError,
    integrity,
    make_record,
)
from solver.store.locking import WriterLock

ONE_T = GRID.replace("T_mm = [1.0, 2.0, 3.0]", "T_mm = 1.0")  # 3 designs, L = 4.1, 7.1, 11.1


@pytest.fixture
def grid():
    return parse_grid(GRID, "grid.toml")


def test_a_job_on_a_symlinked_database_fills_its_target_under_its_locks(grid, tmp_path):
    (tmp_path / "data").mkdir()
    real, link = tmp_path / "data" / "real.h5", tmp_path / "link.h5"
    first = grid.points[0]
    with CurveStore(real, mode="a") as db:
        db.put(make_record(first.design, first.settings, fake_curve(first.design)))
    link.symlink_to(real)
    other_job = WriterLock(tmp_path / "data" / "real.h5.job.lock")  # a job on the target
    other_job.acquire()
    try:
        with pytest.raises(StoreBusyError, match="another precompute job"):
            precompute(grid, link, solve_fn=always_ok_solve, progress=False)
    finally:
        other_job.release()
    summary = precompute(grid, link, solve_fn=always_ok_solve, progress=False)
    assert (summary.skipped_done, summary.complete) == (1, 8)
    assert link.is_symlink()  # not replaced by a file of its own
    with CurveStore(real) as db:
        assert len(db) == 9


def test_a_second_job_is_refused_naming_the_database_with_exit_2(tmp_path, capsys):
    grid_path, db_path = tmp_path / "grid.toml", tmp_path / "f3.h5"
    grid_path.write_text(ONE_T)
    other_job = WriterLock(tmp_path / "f3.h5.job.lock")
    other_job.acquire()
    try:
        code = main(["precompute", str(grid_path), "--db", str(db_path), "--no-progress"])
    finally:
        other_job.release()
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert f"{db_path} is being filled by another precompute job (pid {os.getpid()})" in err
    assert "f3.h5.job " not in err and not db_path.exists()


class LockTakingBackend(InlineBackend):
    """Another writer takes the database's lock after ``take`` results have been stored
    and gives it back after ``give`` (never when None)."""

    def __init__(self, lock: WriterLock, take: int, give: int | None = None) -> None:
        super().__init__()
        self.lock, self.take, self.give = lock, take, give

    def as_completed(self, futures):
        for i, future in enumerate(super().as_completed(futures)):
            if i == self.take:
                self.lock.acquire()
            if i == self.give:
                self.lock.release()
            yield future


def test_solves_finished_while_another_writer_holds_the_lock_are_parked_then_written(
        grid, tmp_path, monkeypatch):
    monkeypatch.setattr("solver.precompute.job.BUSY_RETRY_S", 0.05, raising=False)
    db_path = tmp_path / "c.h5"
    other = WriterLock(tmp_path / "c.h5.lock")
    with CurveStore(db_path, mode="a", hold_lock=False, lock_timeout_s=0.2) as db:
        summary = run_job(grid.points, db, LockTakingBackend(other, take=2, give=6),
                          always_ok_solve, progress=False)
    assert (summary.complete, summary.errors, summary.parked) == (9, 0, 0)
    assert summary.busy is None and not (tmp_path / "c.h5.parked").exists()
    with CurveStore(db_path) as db:
        assert sorted(db.keys()) == sorted(p.key for p in grid.points)


def test_a_lock_held_to_the_end_leaves_every_finished_solve_parked_and_said(
        grid, tmp_path, monkeypatch):
    monkeypatch.setattr("solver.precompute.job.BUSY_RETRY_S", 0.05, raising=False)
    db_path = tmp_path / "c.h5"
    other = WriterLock(tmp_path / "c.h5.lock")
    try:
        with CurveStore(db_path, mode="a", hold_lock=False, lock_timeout_s=0.2) as db:
            summary = run_job(grid.points, db, LockTakingBackend(other, take=3),
                              always_ok_solve, progress=False)
    finally:
        other.release()
    assert (summary.complete, summary.errors, summary.parked) == (9, 0, 6)
    parked = sorted(p.stem for p in (tmp_path / "c.h5.parked").glob("*.h5"))
    assert parked == sorted(p.key for p in grid.points[3:])
    lines = summary.lines()
    assert f"not written: {db_path} is being written by another process" in "\n".join(lines)
    assert f"6 finished results parked in {tmp_path / 'c.h5.parked'}" in "\n".join(lines)
    rerun = precompute(grid, db_path, solve_fn=always_ok_solve, progress=False)
    assert (rerun.unparked, rerun.skipped_done, rerun.to_solve) == (6, 9, 0)


def test_the_command_exits_1_when_finished_solves_are_parked(tmp_path, monkeypatch, capsys):
    grid_path = tmp_path / "grid.toml"
    grid_path.write_text(ONE_T)
    parked = JobSummary(grid_total=3, to_solve=3, complete=3, parked=2, parked_in="d",
                        busy="c.h5 is being written by another process (pid 1)")
    monkeypatch.setattr("solver.precompute.precompute", lambda *a, **k: parked)
    assert main(["precompute", str(grid_path), "--db", str(tmp_path / "c.h5"),
                 "--no-progress"]) == 1
    assert "2 finished results parked in d" in capsys.readouterr().err


def damaged_record_database(path: Path, records: list, bad: int, sealed: bool) -> None:
    """``records`` stored unsealed with record ``bad``'s curve damaged, then, with
    ``sealed``, a seal put over it (what `db seal` or a put of earlier code did)."""
    with CurveStore(path, mode="a") as db:
        db.put_many(records)
    data = bytearray(path.read_bytes())
    data[:integrity.USERBLOCK_BYTES] = bytes(integrity.USERBLOCK_BYTES)
    path.write_bytes(bytes(data))
    damage_curve(path, records[bad])
    if sealed:
        data = bytearray(path.read_bytes())
        integrity.seal(memoryview(data))
        path.write_bytes(bytes(data))


@pytest.mark.parametrize("sealed", [False, True])
@pytest.mark.parametrize("argv", [[], ["--retry-failed"], ["--dry-run"]])
def test_a_damaged_record_is_not_counted_done_the_job_refuses_with_the_salvage(
        tmp_path, capsys, argv, sealed):
    grid_path, db_path = tmp_path / "grid.toml", tmp_path / "c.h5"
    grid_path.write_text(ONE_T)
    points = load_grid(grid_path).points
    records = [make_record(p.design, p.settings, fake_curve(p.design)) for p in points]
    damaged_record_database(db_path, records, 1, sealed)
    before = db_path.read_bytes()
    code = main(["precompute", str(grid_path), "--db", str(db_path), "--no-progress", *argv])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert f"record {records[1].key[:12]} of {db_path} is damaged" in err
    assert f"balloon db salvage {db_path} -o NEW.h5" in err
    assert db_path.read_bytes() == before


def test_the_salvaged_database_is_completed_by_the_job(tmp_path, capsys):
    db_path, new = tmp_path / "c.h5", tmp_path / "new.h5"
    grid = parse_grid(ONE_T, "grid.toml")
    records = [make_record(p.design, p.settings, fake_curve(p.design)) for p in grid.points]
    damaged_record_database(db_path, records, 2, sealed=False)
    with pytest.raises(DamagedStoreError):
        precompute(grid, db_path, solve_fn=always_ok_solve, progress=False)
    assert main(["db", "salvage", str(db_path), "-o", str(new)]) == 0
    summary = precompute(grid, new, solve_fn=always_ok_solve, progress=False)
    assert (summary.skipped_done, summary.to_solve, summary.complete) == (2, 1, 1)
    with CurveStore(new) as db:
        assert len(db) == 3 and not db.damaged_records()


KILLED_RUNNER = """
import sys
from solver.precompute import load_grid, precompute
from test_precompute_fakes import pid_sleeping_solve
if __name__ == "__main__":
    precompute(load_grid(sys.argv[1]), sys.argv[2], workers=2, solve_fn=pid_sleeping_solve,
               progress=False)
"""


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie waiting for a parent that never reaps it does not)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError, IndexError):
        return False
    return state != "Z"


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_workers_end_when_the_job_is_killed_with_sigkill(tmp_path):
    grid_path, pids_dir = tmp_path / "grid.toml", tmp_path / "pids"
    grid_path.write_text(ONE_T)
    pids_dir.mkdir()
    runner = tmp_path / "runner.py"
    runner.write_text(textwrap.dedent(KILLED_RUNNER))
    job = subprocess.Popen([sys.executable, str(runner), grid_path, tmp_path / "c.h5"],
                           env={**ENV, "BALLOON_FAKE_PIDS": str(pids_dir)},
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers: list[int] = []
    try:
        deadline = time.monotonic() + 240  # a bound for a broken run on a loaded machine
        while len(workers) < 2 and time.monotonic() < deadline and job.poll() is None:
            time.sleep(0.1)
            workers = [int(p.name) for p in pids_dir.iterdir()]
        assert len(workers) == 2, "the workers did not start solving"
        os.kill(job.pid, signal.SIGKILL)  # the job only: its workers are left to notice
        job.wait()
        deadline = time.monotonic() + 10
        while any(alive(pid) for pid in workers) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not [pid for pid in workers if alive(pid)], "workers outlived the job"
    finally:
        for pid in workers:  # this test's own processes, if the check failed
            if alive(pid):
                os.kill(pid, signal.SIGKILL)
        if job.poll() is None:
            job.kill()
            job.wait()


def test_a_release_interrupted_by_ctrl_c_can_be_called_again(tmp_path, monkeypatch):
    """Ctrl-C (KeyboardInterrupt) inside a release, as the descriptor is closed: the
    outer ``finally`` releases again, and that must neither raise nor touch the closed
    descriptor (it raised OSError: Bad file descriptor, and under load the number may
    already be another file's). The lock is free for the next writer after it."""
    import solver.store.locking as locking

    lock = WriterLock(tmp_path / "c.h5.lock")
    lock.acquire()
    real_close = os.close

    def close_then_interrupt(fd: int) -> None:
        real_close(fd)
        raise KeyboardInterrupt

    monkeypatch.setattr(locking.os, "close", close_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        lock.release()
    monkeypatch.setattr(locking.os, "close", real_close)
    lock.release()                       # the outer finally's call: a no-op now
    assert not lock.held
    nxt = WriterLock(tmp_path / "c.h5.lock")
    nxt.acquire()
    nxt.release()
