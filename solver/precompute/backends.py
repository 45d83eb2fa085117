"""Where the solves run: a local process pool or a Dask cluster, behind one interface.

Both offer ``submit(fn, *args) -> future``, ``as_completed(futures)``, ``abort(futures)``
and ``close()``; futures have ``result()``, ``done()`` and ``cancel()``. The job's loop
is the same code for both. Results travel back to the parent, which alone writes the
database.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent import futures as cf
from typing import Any

THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
PARENT_CHECK_S = 1.0   # how often a worker looks for its parent
ORPHAN_EXIT_CODE = 70  # a worker that outlived its job ends with this status


def _init_worker(parent_pid: int) -> None:
    """In each worker, before its first solve: Ctrl-C is left to the parent, which stops
    the workers itself; and a daemon thread ends the worker once the parent is gone.
    The parent's SIGTERM handler stops the workers, but ``kill -9`` of the job tells them
    nothing: re-parented, they would solve on and then wait for work for ever."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_exit_when_orphaned, args=(parent_pid,), daemon=True,
                     name="balloon-parent-watch").start()


def _exit_when_orphaned(parent_pid: int) -> None:
    """Compare the worker's parent with the job's pid every PARENT_CHECK_S (a wake-up a
    second: nothing a solve notices) and end the process at once when they differ (the
    job died; the worker was re-parented), whatever the solve is doing."""
    while os.getppid() == parent_pid:
        time.sleep(PARENT_CHECK_S)
    os._exit(ORPHAN_EXIT_CODE)


class PoolBackend:
    """``workers`` spawned processes (spawn: no inherited HDF5 handles or threads).

    Each worker's BLAS/OpenMP threads are capped at cores // workers (unless the user set
    OMP_NUM_THREADS etc.), so N workers do not oversubscribe the machine; the children
    inherit the setting from the environment, which ``close`` restores. A worker whose
    parent dies (``kill -9`` of the job) ends itself within PARENT_CHECK_S.
    """

    def __init__(self, workers: int) -> None:
        self.workers = workers
        threads = str(max(1, (os.cpu_count() or 1) // workers))
        self._saved_env = {name: os.environ.get(name) for name in THREAD_VARIABLES}
        for name in THREAD_VARIABLES:
            os.environ.setdefault(name, threads)
        self._pool = cf.ProcessPoolExecutor(
            max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
            initializer=_init_worker, initargs=(os.getpid(),))

    def submit(self, fn: Callable[..., Any], *args: Any) -> cf.Future:
        return self._pool.submit(fn, *args)

    def as_completed(self, fs: Iterable[cf.Future]) -> Iterator[cf.Future]:
        return cf.as_completed(list(fs))

    def abort(self, fs: Iterable[cf.Future]) -> None:
        """Cancel what has not started and stop the running solves now."""
        for f in fs:
            f.cancel()
        processes = list(getattr(self._pool, "_processes", {}).values())
        for p in processes:
            p.terminate()
        self.close()

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)
        for name, value in self._saved_env.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value

    def describe(self) -> str:
        return f"{self.workers} local worker process{'es' if self.workers > 1 else ''}"


class DaskBackend:
    """A dask.distributed Client: to a scheduler ``address``, or a given client."""

    def __init__(self, address: str | None = None, client: Any = None,
                 timeout_s: float = 30.0) -> None:
        from solver.errors import InputError

        try:
            from distributed import Client  # the optional 'cluster' extra
        except ImportError:
            raise InputError("--scheduler", "Dask distributed is not installed",
                             "pip install 'balloon-actuator[cluster]'") from None
        self._own = client is None
        if client is None:
            try:
                client = Client(address, timeout=timeout_s)
            except (OSError, TimeoutError) as exc:
                raise InputError("--scheduler", f"cannot reach the Dask scheduler at "
                                 f"{address!r} ({exc})", "a running scheduler's address, "
                                 "e.g. tcp://host:8786") from None
        self.client = client

    def submit(self, fn: Callable[..., Any], *args: Any) -> Any:
        return self.client.submit(fn, *args, pure=False)

    def as_completed(self, fs: Iterable[Any]) -> Iterator[Any]:
        from distributed import as_completed

        return iter(as_completed(list(fs)))

    def abort(self, fs: Iterable[Any]) -> None:
        self.client.cancel(list(fs))

    def close(self) -> None:
        if self._own:
            self.client.close()

    def describe(self) -> str:
        workers = len(self.client.scheduler_info().get("workers", {}))
        return f"Dask scheduler {self.client.scheduler.address} ({workers} workers)"
