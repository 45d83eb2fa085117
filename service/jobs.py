"""FE solve jobs: a bounded queue, worker processes, progress, cancel and a time limit.

A ``JobManager`` owns ``workers`` threads. Each takes the oldest queued job and runs
``solve_fn(design, settings, on_step=...)`` in a fresh worker *process* (``spawn``),
so the FE solve never blocks the server's event loop and can be killed. The child
sends every converged step (the solver's ``on_step`` info: step, pressure_pa,
volume_ul, angle_deg, newton_iterations) through a pipe; the thread records it as
the job's progress, enforces ``time_limit_s`` and honours cancellation by
terminating the process. A finished curve is handed to ``write_fn(design, settings,
curve) -> curve id``, which the server serialises: one writer of the database.

Job states: queued -> running -> finished | parked | failed | cancelled | timed_out
(a queued job may also be cancelled). ``finished`` means the curve is stored; the
curve's own status (complete / stopped / failed) is reported beside it. ``parked``: the
solve finished but the database could not take it (disk full, read-only): the result
is kept beside the database and written with the next write that succeeds
(``service.store_access.ResultWriter``).

Jobs live in memory: a restart forgets them (the stored curves remain).
"""

from __future__ import annotations

import multiprocessing
import threading
import time
import uuid
from collections import OrderedDict, deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from typing import Any

from service._worker import child_main
from service.errors import ConflictError, QueueFullError, short_input
from service.store_access import ResultParkedError
from solver.errors import NotFoundError

SolveFn = Callable[..., Any]
WriteFn = Callable[[Any, Any, Any], str]

ACTIVE = ("queued", "running")


def _ended(job: JobState) -> ConflictError:
    """A cancel of a job that has ended (or that another cancel ended): 409."""
    return ConflictError(f"job {job.id} is already {job.status}", job_status=job.status)


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


@dataclass(frozen=True)
class JobState:
    """A snapshot of one job (the manager replaces it on every change)."""

    id: str
    key: str
    design: Any
    settings: Any
    status: str = "queued"
    created_utc: str = field(default_factory=_now)
    started_utc: str | None = None
    finished_utc: str | None = None
    progress: dict[str, Any] = field(default_factory=lambda: {"step": 0})
    curve_id: str | None = None
    curve_status: str | None = None
    curve_reason: str | None = None
    error: str | None = None

    @property
    def active(self) -> bool:
        return self.status in ACTIVE


class JobManager:
    """Queue, run, observe and cancel solve jobs; see the module docstring."""

    def __init__(self, solve_fn: SolveFn, write_fn: WriteFn, *, workers: int = 1,
                 queue_size: int = 8, time_limit_s: float = 900.0, retry_after_s: int = 30,
                 history: int = 1000, poll_s: float = 0.05, mp_context: str = "spawn") -> None:
        self._solve_fn = solve_fn
        self._write_fn = write_fn
        self.workers = workers
        self.queue_size = queue_size
        self.time_limit_s = time_limit_s
        self.retry_after_s = retry_after_s
        self._history = history
        self._poll_s = poll_s
        self._ctx: Any = multiprocessing.get_context(mp_context)
        self._cond = threading.Condition()
        self._jobs: OrderedDict[str, JobState] = OrderedDict()
        self._pending: deque[str] = deque()
        self._cancel: set[str] = set()
        self._storing: set[str] = set()     # solves finished, their curves being written
        self._threads: list[threading.Thread] = []
        self._stopping = False

    # -- life cycle -------------------------------------------------------------------
    def start(self) -> None:
        for i in range(self.workers):
            thread = threading.Thread(target=self._worker, name=f"balloon-job-{i}",
                                      daemon=True)
            thread.start()
            self._threads.append(thread)

    def shutdown(self, timeout_s: float = 5.0) -> None:
        """Stop taking jobs; running ones are terminated and marked cancelled."""
        with self._cond:
            self._stopping = True
            self._cancel.update(j.id for j in self._jobs.values() if j.active)
            self._cond.notify_all()
        for thread in self._threads:
            thread.join(timeout_s)

    # -- the API the routes use --------------------------------------------------------
    def submit(self, design: Any, settings: Any, key: str) -> JobState:
        """Queue a solve; an active job for the same key is returned instead of a new one.

        Raises QueueFullError when ``queue_size`` jobs are already waiting for a worker
        (``queue_size`` 0: accept only what an idle worker can start now).
        """
        with self._cond:
            for job in self._jobs.values():
                if job.key == key and job.active:
                    return job
            # a pending job that an idle worker is about to take is not waiting
            running = sum(1 for j in self._jobs.values() if j.status == "running")
            idle = max(0, self.workers - running)
            if len(self._pending) >= self.queue_size + idle:
                raise QueueFullError(
                    f"the solve queue is full ({self.queue_size} jobs waiting); "
                    f"retry in {self.retry_after_s} s", retry_after_s=self.retry_after_s)
            job = JobState(id=uuid.uuid4().hex, key=key, design=design, settings=settings)
            self._jobs[job.id] = job
            self._pending.append(job.id)
            self._forget_old()
            self._cond.notify()
            return job

    def get(self, job_id: str) -> JobState:
        with self._cond:
            try:
                return self._jobs[job_id]
            except KeyError:
                raise NotFoundError(f"no job {short_input(job_id)} (jobs are kept in "
                                    "memory until the server restarts)") from None

    def cancel(self, job_id: str, wait_s: float = 10.0) -> JobState:
        """Cancel a queued or running job; a running one is terminated (waits for it).

        Idempotent as RFC 9110 9.2.2 means it: the job ends cancelled however many
        cancels arrive, and exactly one of them is the one that cancelled it. The others
        -- after it, or beside it while its worker process is being stopped -- raise
        ConflictError (409: the job's state conflicts with the request, as for a job that
        already ended), once the job has ended, naming its status. A job whose solve has
        finished is no longer cancelled: its curve is being stored (ConflictError at once)
        or stored (its status), never half written nor dropped."""
        deadline = time.monotonic() + wait_s
        with self._cond:
            job = self.get(job_id)
            if not job.active:
                raise _ended(job)
            if job.status == "queued":
                self._pending.remove(job_id)
                return self._update(job_id, status="cancelled", finished_utc=_now())
            if job_id in self._storing:
                raise ConflictError(f"job {job_id}'s solve has finished and its curve is "
                                    "being stored; it can no longer be cancelled",
                                    job_status=job.status)
            another = job_id in self._cancel
            self._cancel.add(job_id)
            while self._jobs[job_id].active and time.monotonic() < deadline:
                self._cond.wait(deadline - time.monotonic())
            job = self._jobs[job_id]
            if another and job.active:      # the first cancel's process still stopping
                raise ConflictError(f"job {job_id} is already being cancelled",
                                    job_status=job.status)
            if another or job.status not in ("cancelled", "running"):
                raise _ended(job)
            return job

    def stats(self) -> dict[str, int]:
        with self._cond:
            running = sum(1 for j in self._jobs.values() if j.status == "running")
            return {"workers": self.workers, "running": running,
                    "queued": len(self._pending), "queue_size": self.queue_size}

    # -- internals ----------------------------------------------------------------------
    def _update(self, job_id: str, **changes: Any) -> JobState:
        """Replace a job's snapshot (call with the condition held)."""
        job = replace(self._jobs[job_id], **changes)
        self._jobs[job_id] = job
        self._cond.notify_all()
        return job

    def _forget_old(self) -> None:
        finished = [j.id for j in self._jobs.values() if not j.active]
        for job_id in finished[:max(0, len(finished) - self._history)]:
            del self._jobs[job_id]

    def _worker(self) -> None:
        while True:
            with self._cond:
                while not self._pending and not self._stopping:
                    self._cond.wait()
                if self._stopping:
                    return
                job = self._update(self._pending.popleft(), status="running",
                                   started_utc=_now())
            try:
                self._run(job)
            except Exception as exc:  # noqa: BLE001 - a job never kills its worker thread
                with self._cond:
                    self._cancel.discard(job.id)
                    self._storing.discard(job.id)
                    self._update(job.id, status="failed", finished_utc=_now(),
                                 error=f"internal error: {type(exc).__name__}: {exc}")

    def _run(self, job: JobState) -> None:
        receiver, sender = self._ctx.Pipe(duplex=False)
        proc = self._ctx.Process(target=child_main, daemon=True,
                                 args=(self._solve_fn, job.design, job.settings, sender))
        proc.start()
        sender.close()
        deadline = time.monotonic() + self.time_limit_s
        outcome: dict[str, Any] = {}
        try:
            while not outcome:
                if job.id in self._cancel:
                    outcome = {"status": "cancelled"}
                elif time.monotonic() > deadline:
                    outcome = {"status": "timed_out", "error": f"the solve exceeded the "
                               f"time limit of {self.time_limit_s:g} s and was stopped"}
                elif receiver.poll(self._poll_s):
                    outcome = self._receive(job, receiver, proc)
        finally:
            if proc.is_alive():
                proc.terminate()
                proc.join(2.0)
                if proc.is_alive():
                    proc.kill()
            proc.join(2.0)
            receiver.close()
        curve = outcome.pop("curve", None)
        if curve is not None:
            with self._cond:    # from here on a cancel is refused: the result is kept
                self._storing.add(job.id)
            try:
                curve_id = self._write_fn(job.design, job.settings, curve)
                outcome = {"status": "finished", "curve_id": curve_id,
                           "curve_status": getattr(curve, "status", None),
                           "curve_reason": getattr(curve, "reason", None) or None}
            except ResultParkedError as exc:
                outcome = {"status": "parked", "error": str(exc),
                           "curve_status": getattr(curve, "status", None),
                           "curve_reason": getattr(curve, "reason", None) or None}
            except Exception as exc:  # noqa: BLE001 - reported as the job's error
                outcome = {"status": "failed",
                           "error": f"the solve finished but storing it failed: {exc}"}
        with self._cond:
            self._cancel.discard(job.id)
            self._storing.discard(job.id)
            self._update(job.id, finished_utc=_now(), **outcome)

    def _receive(self, job: JobState, receiver: Any, proc: Any) -> dict[str, Any]:
        """Handle one message from the worker process; a non-empty dict ends the job."""
        try:
            kind, payload = receiver.recv()
        except (EOFError, OSError):
            proc.join(1.0)
            return {"status": "failed",
                    "error": f"the worker process ended unexpectedly (exit code "
                             f"{proc.exitcode})"}
        if kind == "step":
            with self._cond:
                self._update(job.id, progress=dict(payload))
            return {}
        if kind == "done":
            return {"curve": payload}
        return {"status": "failed", "error": str(payload)}
