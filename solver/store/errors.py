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


# what reading a damaged file or record raises inside h5py and the schema's checks
READ_ERRORS = (BalloonError, OSError, KeyError, RuntimeError, ValueError, TypeError,
               IndexError)
MAX_KEYS_NAMED = 10


def salvage_hint(path: Path | str) -> str:
    """What a user can do with a damaged database (the command that does it)."""
    return (f"restore it from a copy, or copy its intact records to a new file with "
            f"`balloon db salvage {path} -o NEW.h5`; `balloon precompute` on NEW.h5 then "
            f"solves the lost designs again")


def _records_of(records: tuple[str, ...]) -> str:
    """The words naming ``records`` before a file's name: ``record K of`` or ``records
    K1, K2 of`` (keys cut to 12 digits, at most MAX_KEYS_NAMED of them)."""
    if not records:
        return ""
    shown = ", ".join(k[:12] for k in records[:MAX_KEYS_NAMED])
    if len(records) > MAX_KEYS_NAMED:
        shown += f" and {len(records) - MAX_KEYS_NAMED} more"
    return f"record{'s' if len(records) > 1 else ''} {shown} of "


class DamagedStoreError(NotACurveStoreError):
    """Reading the database failed inside the file: bytes damaged (flipped, not only
    truncated), a record unreadable or inconsistent with its key. ``name`` is the file's
    name (no directory), ``record`` the key when one record is at fault, ``records``
    every key named (one or more). The allowed action names `balloon db salvage`."""

    def __init__(self, path: Path, cause: str, record: str | None = None,
                 records: tuple[str, ...] | list[str] = ()) -> None:
        self.path, self.name, self.cause = Path(path), Path(path).name, cause
        self.records = tuple(records) or ((record,) if record else ())
        self.record = record or (self.records[0] if self.records else None)
        super().__init__("db", f"{self._where()}{path} {self._verb()} damaged ({cause})",
                         salvage_hint(path))

    def _where(self) -> str:
        return _records_of(self.records)

    def _verb(self) -> str:
        return "are" if len(self.records) > 1 else "is"

    def public(self) -> str:
        """The message with the file's name only (for HTTP answers)."""
        return f"{self._where()}the curve database {self.name} {self._verb()} damaged " \
               f"({self.cause})"


class StoreWriteError(BalloonError):
    """The database could not be written (disk full, read-only file system, no
    permission): the published file is untouched. Names the path and the cause."""

    def __init__(self, path: Path, exc: BaseException) -> None:
        self.path, self.cause = Path(path), cause_of(exc, Path(path))
        super().__init__(f"cannot write {path}: {self.cause}; the database is unchanged")
