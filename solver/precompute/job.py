"""The precompute job: solve every grid design missing from the database.

    plan       grid points minus what the database already holds (complete or stopped
               records; failed ones too unless ``retry_failed``)
    submit     every missing design to the backend (process pool or Dask), in grid order
    collect    as each solve finishes, the parent -- the database's only writer -- puts
               its record at once (an atomic publish), so a crash loses at most the
               solves in flight
    summarise  counts, failures, designs per hour

A solve that fails (a "failed" curve, or an exception in the solve function) is
stored as a failed record with its reason and does not stop the job. A worker that
dies (out of memory, killed) is counted under ``errors`` and stored as nothing: a
rerun tries that design again. Ctrl-C stops the workers, stores what had already
finished, and returns a summary with ``interrupted = True``. A write that fails (disk
full, read-only file system: StoreWriteError) stops the job the same way, with
``write_error`` naming the path and the cause; the database is untouched and the
finished results are parked (``solver.precompute.parking``) and written first by the
next run. Another writer that holds the database's lock past the store's wait (60 s)
stops nothing: each result finished meanwhile is parked at once, and written, with the
parked ones, by the first put that gets the lock again (at the latest at the job's end,
else by the next run); a finished solve is never dropped.

The job starts only on a database whose records all read back (``refuse_damaged``).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from solver.curve import Curve
from solver.design import Design
from solver.precompute.grid import GridPoint
from solver.precompute.parking import park, unpark
from solver.settings import SolverSettings
from solver.store import (
    CurveStore,
    Record,
    StoreBusyError,
    StoreWriteError,
    failed_curve,
    make_record,
)
from solver.store.locking import JOB_SUFFIX, WriterLock, database_path, lock_path
from solver.store.record import git_commit, package_version, utc_now

SolveFn = Callable[[Design, SolverSettings], Curve]
BUSY_RETRY_S = 1.0  # the lock's wait once another writer held it past the store's wait


def default_solve(design: Design, settings: SolverSettings) -> Curve:
    """``solver.stepping.solve``, imported in the worker, so the parent never loads the FE
    stack."""
    from solver.stepping import solve

    return solve(design, settings)


def solve_point(design: Design, settings: SolverSettings, solve_fn: SolveFn) -> Record:
    """Run in a worker: solve one design and wrap the curve in a Record with provenance.
    Exceptions of the solve become failed records; only the worker dying escapes."""
    start = time.perf_counter()
    try:
        curve = solve_fn(design, settings)
    except Exception as exc:  # noqa: BLE001 - any solve error is recorded, not raised
        curve = failed_curve(f"{type(exc).__name__}: {exc}", time.perf_counter() - start)
    return make_record(design, settings, curve, wall_time_s=time.perf_counter() - start)


def describe(design: Design) -> str:
    return (f"L={design.L_mm:g} t={design.t_mm:g} mm "
            f"{design.body_material.id}/{design.membrane_material.id}")


@dataclass
class JobSummary:
    """What a run did. Counts are designs; ``wall_time_s`` is the whole run, s."""

    grid_total: int = 0
    skipped_done: int = 0          # already complete or stopped in the database
    skipped_failed: int = 0        # already failed, not retried (no --retry-failed)
    to_solve: int = 0
    complete: int = 0
    stopped: int = 0
    failed: int = 0                # stored as failed records
    errors: int = 0                # worker died or result lost: nothing stored
    interrupted: bool = False
    write_error: str | None = None  # the database could not be written: why
    busy: str | None = None        # another writer holds the lock (results parked): who
    parked: int = 0                # finished results parked, not written (written next run)
    parked_in: str = ""
    run_recorded: bool = True      # the run's end is in the file's metadata
    unparked: int = 0              # parked results of an earlier run written this run
    wall_time_s: float = 0.0
    backend: str = ""
    failures: list[tuple[str, str, str]] = field(default_factory=list)  # key, design, reason

    @property
    def solved(self) -> int:
        return self.complete + self.stopped + self.failed

    @property
    def not_run(self) -> int:
        return self.to_solve - self.solved - self.errors

    def _busy_lines(self) -> list[str]:
        """Results parked while another writer held the lock, if any are left."""
        if not self.parked:
            return []
        return [f"not written: {self.busy}",
                f"{self.parked} finished results parked in {self.parked_in}; rerun the same "
                "command when the database is free: they are written first, not solved "
                "again"]

    @property
    def designs_per_hour(self) -> float:
        return 3600.0 * self.solved / self.wall_time_s if self.wall_time_s > 0 else 0.0

    def lines(self) -> list[str]:
        out = [f"wrote {self.unparked} results parked by an earlier run"] if self.unparked \
            else []
        out += [f"grid: {self.grid_total} designs; already in the database: "
               f"{self.skipped_done} done, {self.skipped_failed} failed (skipped)",
               f"solved {self.solved} of {self.to_solve} on {self.backend} in "
               f"{self.wall_time_s:.1f} s ({self.designs_per_hour:.0f} designs/h): "
               f"{self.complete} complete, {self.stopped} stopped, {self.failed} failed"]
        if self.errors:
            out.append(f"{self.errors} lost to worker errors (nothing stored; rerun to retry)")
        if self.write_error:
            out.append(f"stopped: {self.write_error}")
            if self.parked:
                out.append(f"{self.parked} finished results parked in {self.parked_in}; "
                           "fix the cause and rerun the same command: they are written "
                           f"first, then the {self.not_run} not run are solved")
        else:
            out += self._busy_lines()
            if self.interrupted:
                out.append(f"interrupted: {self.not_run} not run; rerun the same command "
                           f"to continue (finished records are kept)")
        if not self.run_recorded:
            out.append(f"the run's end is not recorded in the file's metadata ({self.busy})")
        for key, design, reason in self.failures[:20]:
            out.append(f"  failed {key[:12]} {design}: {reason}")
        if len(self.failures) > 20:
            out.append(f"  ... and {len(self.failures) - 20} more (balloon db ls --status "
                       f"failed)")
        return out


def plan(points: Sequence[GridPoint], statuses: dict[str, str],
         retry_failed: bool = False) -> tuple[list[GridPoint], JobSummary]:
    """The points still to solve, and a summary with the skip counts filled in."""
    summary = JobSummary(grid_total=len(points))
    todo = []
    for point in points:
        status = statuses.get(point.key)
        if status in ("complete", "stopped"):
            summary.skipped_done += 1
        elif status == "failed" and not retry_failed:
            summary.skipped_failed += 1
        else:
            todo.append(point)
    summary.to_solve = len(todo)
    return todo, summary


def run_job(points: Sequence[GridPoint], db: CurveStore, backend: Any,
            solve_fn: SolveFn | None = None, retry_failed: bool = False,
            progress: bool = True) -> JobSummary:
    """Solve the missing ``points`` on ``backend``, writing each record to ``db`` (opened
    with mode "a") as soon as it arrives."""
    from tqdm import tqdm

    solve_fn = solve_fn or default_solve
    todo, summary = plan(points, db.statuses(), retry_failed)
    summary.backend = backend.describe()
    start = time.perf_counter()
    futures: dict[Any, GridPoint] = {}
    stored: set[Any] = set()
    bar = tqdm(total=len(todo), desc="precompute", unit="design", file=sys.stderr,
               disable=not progress or not todo, dynamic_ncols=True)

    def store(future: Any) -> None:
        point = futures[future]
        try:
            record = future.result()
        except Exception as exc:  # noqa: BLE001 - a worker died: keep going, store nothing
            summary.errors += 1
            summary.failures.append((point.key, describe(point.design),
                                     f"worker error {type(exc).__name__}: {exc}"))
        else:
            write(record)
            status = record.curve.status
            setattr(summary, status, getattr(summary, status) + 1)
            if status == "failed":
                summary.failures.append((record.key, describe(record.design),
                                         record.curve.reason))
        stored.add(future)  # not before: a put cut short by Ctrl-C is retried below
        bar.update(1)
        counts = {"complete": summary.complete + summary.stopped, "failed": summary.failed}
        if summary.errors:
            counts["worker_errors"] = summary.errors
        bar.set_postfix(counts, refresh=False)
        if summary.write_error:
            raise _WriteFailed  # stop submitting and waiting: park what has finished

    def write(record: Record) -> None:
        """Put ``record`` now, after the results parked while another writer held the
        lock; park it when the database cannot take it (full disk: the job stops; the
        lock held past the wait: the job goes on, waiting BUSY_RETRY_S a result until
        the lock is free, and after Ctrl-C)."""
        if summary.write_error is not None:
            park_result(record)
            return
        wait = BUSY_RETRY_S if summary.busy or summary.interrupted else None
        try:
            if summary.parked:  # parked while the lock was held: written first
                unpark(db, also=[record], lock_timeout_s=wait)
                summary.parked, summary.busy = 0, None
            else:
                db.put(record, lock_timeout_s=wait)
        except StoreBusyError as exc:
            park_result(record)
            if summary.busy is None and summary.parked and progress:
                bar.write(f"precompute: {exc}; finished results are parked in "
                          f"{summary.parked_in} until it is free", file=sys.stderr)
            summary.busy = str(exc)
        except StoreWriteError as exc:
            summary.write_error = str(exc)
            park_result(record)

    def park_result(record: Record) -> None:
        try:
            summary.parked_in = str(park(record, db.path))
            summary.parked += 1
        except OSError as exc:  # nowhere to park either: say it is lost
            summary.errors += 1
            summary.failures.append((record.key, describe(record.design),
                                     f"finished but lost: cannot park it ({exc})"))

    try:
        for point in todo:
            futures[backend.submit(solve_point, point.design, point.settings, solve_fn)] = point
        for future in backend.as_completed(futures):
            store(future)
    except (KeyboardInterrupt, _WriteFailed):
        summary.interrupted = True
        pending = [f for f in futures if f not in stored]
        finished = [f for f in pending if f.done() and not f.cancelled()]
        backend.abort([f for f in pending if f not in finished])
        for future in finished:  # solves that ended before Ctrl-C: keep them
            try:
                store(future)
            except _WriteFailed:
                continue  # the rest are parked
            except KeyboardInterrupt:
                break
    finally:
        bar.close()
        summary.wall_time_s = time.perf_counter() - start
    return summary


class _WriteFailed(Exception):
    """Internal: the database cannot be written; stop the job, park what finished."""


def precompute(grid: Any, db_path: str | Path, workers: int = 1,
               scheduler: str | None = None, client: Any = None,
               solve_fn: SolveFn | None = None, retry_failed: bool = False,
               progress: bool = True, command: str | None = None,
               metadata: dict[str, object] | None = None) -> JobSummary:
    """Open ``db_path`` as a writer, record this run in the file's metadata (command,
    grid text and hash, versions), run the job, and record how it ended. ``metadata``:
    further file attributes to record with the run (where its designs came from).

    ``grid`` is a ``Grid`` (from ``load_grid``); the backend is a pool of ``workers``
    processes, or Dask when ``scheduler`` (an address) or ``client`` is given.
    One job per database at a time (``<db>.job.lock``; a second one raises
    StoreBusyError); a symbolic link is followed to the file it names, whose locks and
    file are the job's. The writer lock is taken only around each put, so other writers
    (the service storing its own solves) interleave with a long job. A database with a
    damaged record is refused before anything is written (``refuse_damaged``).
    """
    from solver.precompute.backends import DaskBackend, PoolBackend

    path = database_path(db_path)
    job_lock = WriterLock(lock_path(path, JOB_SUFFIX),
                          what="being filled by another precompute job")
    job_lock.acquire()
    try:
        with CurveStore(path, mode="a", hold_lock=False) as db:
            refuse_damaged(db)
            run = {"command": command or "", "grid_source": grid.source,
                   "grid_sha256": grid.sha256, "started_utc": utc_now(),
                   "package_version": package_version(), "git_commit": git_commit()}
            db.set_metadata(generator_command=command or "", grid_toml=grid.text,
                            runs=[*db.metadata.get("runs", []), run], **(metadata or {}))
            unparked = unpark(db)  # results an earlier run could not write
            backend = (DaskBackend(scheduler, client) if scheduler or client is not None
                       else PoolBackend(workers))
            try:
                summary = run_job(grid.points, db, backend, solve_fn, retry_failed, progress)
            finally:
                backend.close()
            summary.unparked = unparked
            if summary.parked and not summary.write_error:
                _write_parked(db, summary)
            if summary.write_error or summary.parked:  # nor can it take the run's end
                return summary
            runs = list(db.metadata.get("runs", []))
            runs[-1] = {**run, "finished_utc": utc_now(), "interrupted": summary.interrupted,
                        "solved": summary.solved, "failed": summary.failed,
                        "errors": summary.errors}
            try:
                db.set_metadata(runs=runs)
            except StoreBusyError as exc:  # every record is stored; only this line is not
                summary.busy, summary.run_recorded = str(exc), False
        return summary
    finally:
        job_lock.release()


def refuse_damaged(db: CurveStore) -> None:
    """DamagedStoreError (one line, exit 2 from the CLI) naming every record of ``db``
    that does not read back, with the salvage command; nothing when all do.

    Refused rather than solved again: a damaged record says that something other than
    this code changed the file (a failing disk, another tool), so its other records and
    its next writes are suspect too; its design and settings may be what changed, so
    the grid point it stood for is unknown; and every publish would put a fresh seal
    over it. `balloon db salvage DB -o NEW.h5` copies the intact records to a new file,
    which this job then completes (the damaged designs are missing there, so solved
    again). Costs one full read of every record (about 5 ms each) before the first solve."""
    db.require_intact()


def _write_parked(db: CurveStore, summary: JobSummary) -> None:
    """At the job's end, the results parked while another writer held the lock: written
    if the lock comes within the store's wait (BUSY_RETRY_S after Ctrl-C), else left
    parked for the next run."""
    try:
        unpark(db, lock_timeout_s=BUSY_RETRY_S if summary.interrupted else None)
    except StoreBusyError as exc:
        summary.busy = str(exc)
        return
    summary.parked, summary.busy = 0, None
