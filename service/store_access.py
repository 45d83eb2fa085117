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
    """Open the database read-only; 503 when it is missing, damaged (at opening or while
    a request reads it) or of a newer schema: a server-side condition, not the client's
    input. The answers name the file by its name, never its directory."""
    from solver.store import CurveStore, NotACurveStoreError, SchemaVersionError

    path = Path(path)
    if not path.is_file():
        raise UnavailableError(f"no curve database {path.name} on the server (set "
                               "BALLOON_DB_PATH, or run `balloon precompute`)")
    try:
        store = CurveStore(path, mode="r")
        try:
            store.metadata  # noqa: B018 - opens the file now, so its errors are mapped here
        except BaseException:
            store.close()
            raise
    except (OSError, NotFoundError, NotACurveStoreError, SchemaVersionError) as exc:
        raise UnavailableError(_unreadable(path, exc), retry_after_s=5) from None
    with store as db:
        try:
            yield db
        except NotACurveStoreError as exc:  # DamagedStoreError while reading a record
            raise UnavailableError(_unreadable(path, exc), retry_after_s=5) from None


def _unreadable(path: Path, exc: BaseException) -> str:
    return f"the curve database cannot be read: {_public(path, exc)}"


def _public(path: Path, exc: BaseException) -> str:
    """A store error's words with the database named by its name, not its path."""
    public = getattr(exc, "public", None)
    return public() if public else str(exc).replace(str(path), path.name)


def database_state(path: Path) -> tuple[int | None, str | None]:
    """(records, problem) of the database: (None, None) when there is none, (None, why)
    when it cannot be read; re-read only when the file changes (the store publishes a new
    file on every write). Every record's index entry is read, not the curves."""
    try:
        st = os.stat(path)
    except OSError:
        return None, None
    return _state(str(path), st.st_ino, st.st_mtime_ns, st.st_size)


@lru_cache(maxsize=8)
def _state(path: str, inode: int, mtime_ns: int, size: int) -> tuple[int | None, str | None]:
    try:
        with open_store(Path(path)) as db:
            return len(db.statuses()), None
    except BalloonError as exc:
        return None, str(exc)


# Every record's summary row (no curves) of one version of the database file, read once:
# the store publishes a new file on every write, so (path, inode, mtime, size) names a
# version. /v1/curves and the plot's nearby FE curves read them from here. A sealed file
# of this code gives them from its summary index (0.06 s for the shipped 2403 records);
# a file of older code from every record's attributes (16 s: docs/database.md). Not read
# at start-up in a thread: h5py objects freed by the collector in one thread while
# another reads hung a test client for 10 minutes (h5py's object lock).
_SUMMARIES: dict[tuple, tuple[dict[str, Any], ...]] = {}
_SUMMARIES_LOCK = threading.Lock()


def file_version(path: Path) -> tuple[str, int, int, int]:
    """The database file's version: (path, inode, mtime, size); OSError when absent."""
    st = os.stat(path)
    return str(path), st.st_ino, st.st_mtime_ns, st.st_size


def summary_rows(version: tuple, db: Any) -> tuple[dict[str, Any], ...]:
    """Every record's summary row (``CurveStore.summaries``) of the file ``version``
    (``file_version``, taken before ``db`` was opened: a write in between keeps newer rows
    under the older version, which no later request asks for -- the reverse would serve
    stale rows); only the current version is kept."""
    with _SUMMARIES_LOCK:
        rows = _SUMMARIES.get(version)
    if rows is None:
        rows = tuple(db.summaries())
        with _SUMMARIES_LOCK:
            _SUMMARIES.clear()
            _SUMMARIES[version] = rows
    return rows


def stored_key(path: Path, key: str) -> bool:
    """Whether the database holds ``key`` (False when there is no database yet)."""
    if not Path(path).is_file():
        return False
    with open_store(path) as db:
        return key in db


class ResultParkedError(BalloonError):
    """The solve finished but the database could not take it (disk full, read-only file
    system, a damaged record that a publish would seal over): the record is parked
    beside it (``solver.precompute.parking``, as the precompute job does) and written
    with the next write that succeeds. The message names the database by its name only
    (clients read it); ``then`` says what to do first, where waiting does not help."""

    def __init__(self, key: str, name: str, cause: str, then: str = "") -> None:
        super().__init__(f"the solve finished but the curve database {name} cannot be "
                         f"written ({cause}); the result is kept (parked) and written with "
                         f"the next write that succeeds{then}")
        self.key = key


def _after_salvage(name: str) -> str:
    """What to run when the database holds a damaged record (no put seals over one)."""
    return (f": run `balloon db salvage {name} -o NEW.h5` where the server's database "
            f"is and put NEW.h5 in place of {name} (the damaged records are named; "
            "`balloon precompute` solves them again), then the next solve writes the "
            "parked results")


class ResultWriter:
    """``writer(design, settings, curve) -> key``: store one finished solve, after the
    results parked by earlier failed writes; when the database cannot be written, park
    it and raise ResultParkedError (nothing finished is lost)."""

    def __init__(self, path: Path, busy_wait_s: float = 600.0) -> None:
        self.path = Path(path)
        self.busy_wait_s = busy_wait_s
        self._lock = threading.Lock()

    def __call__(self, design: Any, settings: Any, curve: Any) -> str:
        from solver.precompute.parking import unpark
        from solver.store import CurveStore
        from solver.store.errors import (
            DamagedStoreError,
            NotACurveStoreError,
            StoreBusyError,
            StoreWriteError,
        )
        from solver.store.record import make_record

        record = make_record(design, settings, curve)
        deadline = time.monotonic() + self.busy_wait_s
        with self._lock:
            while True:
                try:
                    with CurveStore(self.path, mode="a") as db:
                        unpark(db)
                        db.put(record)
                    return record.key
                except StoreBusyError:
                    if time.monotonic() > deadline:  # parked, as precompute's past its wait
                        self._park(record, None)
                        raise ResultParkedError(
                            record.key, self.path.name, "its writer lock was held by "
                            f"another writer for the whole wait of {self.busy_wait_s:g} s"
                            ) from None
                    time.sleep(1.0)
                except StoreWriteError as exc:
                    self._park(record, exc)
                    raise ResultParkedError(record.key, self.path.name, exc.cause) from None
                except NotACurveStoreError as exc:  # a damaged record, or no database
                    self._park(record, exc)
                    then = (_after_salvage(self.path.name)
                            if isinstance(exc, DamagedStoreError) else "")
                    raise ResultParkedError(record.key, self.path.name,
                                            _public(self.path, exc), then) from None

    def _park(self, record: Any, exc: BaseException | None) -> None:
        """Park ``record`` beside the database; ResultLostError when no parking directory
        takes it either (then it is lost, and the job says so)."""
        from solver.precompute.parking import park
        from solver.store.errors import cause_of

        try:
            park(record, self.path)
        except OSError as lost:
            raise ResultLostError(self.path.name, cause_of(lost, self.path)) from exc


class ResultLostError(BalloonError):
    """Neither the database nor a parking directory took a finished solve. Names the
    database by its name only (the job's error reaches clients; the store's own
    StoreWriteError names the path)."""

    def __init__(self, name: str, cause: str) -> None:
        super().__init__(f"neither the curve database {name} nor a parking directory (beside "
                         f"it, or ~/.balloon/parked) takes the result ({cause}); it is lost: "
                         "solve it again once the server's disk takes files")
