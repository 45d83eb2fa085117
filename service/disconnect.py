"""Long requests stopped when their client disconnects.

A calibration (``POST /v1/calibrate``, seconds for a lab's data set) or a design search
(``POST /v1/inverse``) runs in a worker thread; the route meanwhile asks the connection
every ``POLL_S`` whether its client is still there. When it is not, the route sets the
work's ``cancel`` event, and the work stops at its next loop boundary (a fit, a
cross-validation, a batch of designs screened: ``surrogate.errors.stop_if_cancelled``)
with ``Cancelled``, which nobody receives (``service.errors`` maps it to 499, the status
proxies log for a client that closed its request). The numerical core knows nothing of
HTTP: it is given a ``threading.Event``.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable
from typing import TypeVar

from starlette.concurrency import run_in_threadpool
from starlette.requests import Request

T = TypeVar("T")
POLL_S = 0.25  # how often the connection is asked, s: the work stops at most this later


async def unless_disconnected(request: Request, work: Callable[[threading.Event], T]) -> T:
    """``work(cancel)`` in a worker thread, its result or its error; ``cancel`` is set
    when the client disconnects (or this coroutine is itself cancelled: a server that
    shuts down), and the work is awaited until it has stopped, so that the thread is
    free when this returns."""
    cancel = threading.Event()
    future = asyncio.ensure_future(run_in_threadpool(work, cancel))
    try:
        while not future.done():
            await asyncio.wait({future}, timeout=POLL_S)
            if not future.done() and not cancel.is_set() and await request.is_disconnected():
                cancel.set()
        return future.result()
    finally:
        cancel.set()
