"""A second core for the assembly: the elements evaluated in two threads.

numpy's array kernels (ufuncs, matmul, einsum, the batched eigh) and scipy's sparse
products release the GIL, so two groups of elements evaluated in threads run on two
cores (``solver.discrete.evaluation_units``); the result is the same to the bit (each
element's arithmetic is unchanged).

The thread budget is the one MKL PARDISO takes for the factorisation: MKL_NUM_THREADS,
else OMP_NUM_THREADS (what the precompute job sets per worker, cores // workers), else
the cores this process may use. ``OMP_NUM_THREADS=1`` keeps everything on one thread.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from typing import TypeVar

T = TypeVar("T")
R = TypeVar("R")

_lock = threading.Lock()
_pool: ThreadPoolExecutor | None = None


def thread_budget() -> int:
    """Threads the solver may use: MKL_NUM_THREADS, else OMP_NUM_THREADS, else the
    usable cores."""
    for name in ("MKL_NUM_THREADS", "OMP_NUM_THREADS"):
        value = os.environ.get(name, "").strip()
        if value.isdigit() and int(value) > 0:
            return int(value)
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                       # not on Linux
        return os.cpu_count() or 1


def _forget_helper() -> None:
    """In a forked child the helper thread does not exist: start a new one on demand."""
    global _lock, _pool
    _lock, _pool = threading.Lock(), None


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_helper)


def _helper() -> ThreadPoolExecutor:
    global _pool
    with _lock:
        if _pool is None:
            _pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="solver-assembly")
        return _pool


def map_pair(fn: Callable[[T], R], items: Sequence[T], split: int | None = None) -> list[R]:
    """``[fn(x) for x in items]``: ``items[split:]`` (default: the last item) on a helper
    thread while the calling thread does the others, when the thread budget allows two
    and both parts are non-empty; otherwise in order on this thread."""
    k = len(items) - 1 if split is None else split
    if not 0 < k < len(items) or thread_budget() < 2:
        return [fn(x) for x in items]
    future = _helper().submit(lambda: [fn(x) for x in items[k:]])
    try:
        head = [fn(x) for x in items[:k]]
    except BaseException:
        wait([future])                           # no work left behind on the helper
        raise
    return head + future.result()
