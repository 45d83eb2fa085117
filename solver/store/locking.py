"""The single-writer lock: an exclusive ``fcntl.flock`` on the sidecar ``<db>.lock`` file.

The kernel drops the lock when its process ends, however it ends (kill -9 included),
so a crashed writer never leaves the database locked. Readers never take it.
"""

from __future__ import annotations

import fcntl
import os
import time
from pathlib import Path

from solver.store.errors import StoreBusyError, StoreWriteError


def lock_path(db_path: Path) -> Path:
    return db_path.with_name(db_path.name + ".lock")


class WriterLock:
    """Exclusive lock; ``acquire`` waits up to ``timeout_s`` (default: not at all), then
    raises StoreBusyError naming the holder's pid. ``what`` words the message."""

    def __init__(self, path: Path, what: str = "being written by another process") -> None:
        self.path = Path(path)
        self.what = what
        self._fd: int | None = None

    @property
    def held(self) -> bool:
        return self._fd is not None

    def acquire(self, timeout_s: float = 0.0) -> None:
        try:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:  # read-only file system, no permission, disk full
            raise StoreWriteError(self.path, exc) from None
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() < deadline:
                    time.sleep(0.02)
                    continue
                holder = os.read(fd, 64).decode("ascii", "replace").strip() or "?"
                os.close(fd)
                raise StoreBusyError(
                    f"{self.path.with_suffix('')} is {self.what} (pid {holder}); a database "
                    f"has a single writer and one precompute job at a time: wait for it to "
                    f"finish or stop it") from None
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode("ascii"))
        self._fd = fd

    def release(self) -> None:
        if self._fd is not None:
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None
