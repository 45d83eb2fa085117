"""The single-writer lock: an exclusive ``fcntl.flock`` on the sidecar ``<db>.lock`` file.

The kernel drops the lock when its process ends, however it ends (kill -9 included),
so a crashed writer never leaves the database locked. Readers never take it.
"""

from __future__ import annotations

import fcntl
import os
from pathlib import Path

from solver.store.errors import StoreBusyError


def lock_path(db_path: Path) -> Path:
    return db_path.with_name(db_path.name + ".lock")


class WriterLock:
    """Non-blocking exclusive lock; ``acquire`` raises StoreBusyError when held elsewhere."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._fd: int | None = None

    def acquire(self) -> None:
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 64).decode("ascii", "replace").strip() or "?"
            os.close(fd)
            raise StoreBusyError(
                f"{self.path.with_suffix('')} is being written by another process (pid "
                f"{holder}); the database has a single writer: wait for it to finish or "
                f"stop it") from None
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode("ascii"))
        self._fd = fd

    def release(self) -> None:
        if self._fd is not None:
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None
