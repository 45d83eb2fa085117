"""The service's access to the curve database: many readers, one serialised writer.

Readers open ``CurveStore(path, "r")`` per request (a reader never sees a
half-written record, and keeps working while ``balloon precompute`` writes).
Finished solve jobs are stored by ``ResultWriter``: one lock in this process, and
the store's own single-writer lock across processes; while another process
(a precompute job) holds the writer lock, the writer waits and retries.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path
from typing import Any

from service.errors import UnavailableError
from solver.errors import BalloonError, NotFoundError


@contextmanager
def open_store(path: Path) -> Iterator[Any]:
    """Open the database read-only; 503 when it is missing, damaged or of a newer schema
    (a server-side condition, not the client's input)."""
    from solver.store import CurveStore, NotACurveStoreError, SchemaVersionError

    if not Path(path).is_file():
        raise UnavailableError(f"no curve database at {path}: set BALLOON_DB_PATH or run "
                               "`balloon precompute` to create one")
    try:
        store = CurveStore(path, mode="r")
        try:
            store.metadata  # noqa: B018 - opens the file now, so its errors are mapped here
        except BaseException:
            store.close()
            raise
    except (OSError, NotFoundError, NotACurveStoreError, SchemaVersionError) as exc:
        raise UnavailableError(f"the curve database cannot be read: {exc}",
                               retry_after_s=5) from None
    with store as db:
        yield db


def record_count(path: Path) -> int | None:
    """Records in the database (None when absent or unreadable); re-read only when the
    file changes (the store publishes a new file on every write)."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return _count(str(path), st.st_ino, st.st_mtime_ns, st.st_size)


@lru_cache(maxsize=8)
def _count(path: str, inode: int, mtime_ns: int, size: int) -> int | None:
    try:
        with open_store(Path(path)) as db:
            return len(db)
    except BalloonError:
        return None


def stored_key(path: Path, key: str) -> bool:
    """Whether the database holds ``key`` (False when there is no database yet)."""
    if not Path(path).is_file():
        return False
    with open_store(path) as db:
        return key in db


class ResultWriter:
    """``writer(design, settings, curve) -> key``: store one finished solve."""

    def __init__(self, path: Path, busy_wait_s: float = 600.0) -> None:
        self.path = Path(path)
        self.busy_wait_s = busy_wait_s
        self._lock = threading.Lock()

    def __call__(self, design: Any, settings: Any, curve: Any) -> str:
        from solver.store import CurveStore
        from solver.store.errors import StoreBusyError
        from solver.store.record import make_record

        record = make_record(design, settings, curve)
        deadline = time.monotonic() + self.busy_wait_s
        with self._lock:
            while True:
                try:
                    with CurveStore(self.path, mode="a") as db:
                        db.put(record)
                    return record.key
                except StoreBusyError:
                    if time.monotonic() > deadline:
                        raise
                    time.sleep(1.0)
