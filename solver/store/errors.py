"""Errors of the curve database (all derive from solver.errors.BalloonError)."""

from __future__ import annotations

import re
from pathlib import Path

from solver.errors import BalloonError, InputError


class SchemaVersionError(BalloonError):
    """The file was written by a newer schema than this code can read."""


class StoreBusyError(BalloonError):
    """Another process already holds the database's single writer lock."""


class NotACurveStoreError(InputError):
    """The file exists but is not a curve database (or is damaged)."""


def cause_of(exc: BaseException, path: Path) -> str:
    """An OS or HDF5 error in a few words, without the file's full path (a server sends
    this text to clients): HDF5's long messages are cut to their ``error message``."""
    text = str(exc)
    messages = re.findall(r"error message = '([^']*)'", text)  # HDF5: the OS's words last
    if messages:
        text = messages[-1]
    elif isinstance(exc, OSError) and exc.strerror:
        text = exc.strerror
    text = " ".join(text.replace(str(path), path.name).split()) or type(exc).__name__
    return f"{type(exc).__name__}: {text}"[:300]


class DamagedStoreError(NotACurveStoreError):
    """Reading the database failed inside the file: bytes damaged (flipped, not only
    truncated), a record unreadable or inconsistent with its key. ``name`` is the file's
    name (no directory), ``record`` the key when one record is at fault."""

    def __init__(self, path: Path, cause: str, record: str | None = None) -> None:
        self.path, self.name, self.record, self.cause = Path(path), Path(path).name, record, cause
        where = f"record {record[:12]} of " if record else ""
        super().__init__("db", f"{where}{path} is damaged ({cause})",
                         "restore it from a copy, or rebuild it with `balloon precompute`")

    def public(self) -> str:
        """The message with the file's name only (for HTTP answers)."""
        where = f"record {self.record[:12]} of " if self.record else ""
        return f"{where}the curve database {self.name} is damaged ({self.cause})"


class StoreWriteError(BalloonError):
    """The database could not be written (disk full, read-only file system, no
    permission): the published file is untouched. Names the path and the cause."""

    def __init__(self, path: Path, exc: BaseException) -> None:
        self.path, self.cause = Path(path), cause_of(exc, Path(path))
        super().__init__(f"cannot write {path}: {self.cause}; the database is unchanged")
