"""The single-writer lock: an exclusive ``fcntl.flock`` on the sidecar ``<db>.lock`` file
(and the precompute job's ``<db>.job.lock``).

The kernel drops the lock when its process ends, however it ends (kill -9 included),
so a crashed writer never leaves the database locked: a lock file whose holder has ended
is taken by the next writer at once, whatever it holds. Readers never take it. The
holder removes its lock file when it lets go (an interrupted command too: Ctrl-C, and
SIGTERM to ``balloon precompute``, end through the release); only a process killed
outright leaves one behind, and that one blocks nothing. The file holds ``<pid>@<host>``
of its holder, which a refused writer is told. Deleting a held lock file would let a
second writer in beside the live one: the refusal says not to, and a writer that locked
a file which has since been removed (its holder let go) locks the file at the path again.

Locks belong to the real file: a database named through a symbolic link is opened at
the link's target (``database_path``), so its writes replace the target (not the link)
and two names of one file share its locks.
"""

from __future__ import annotations

import errno
import fcntl
import os
import socket
import time
from pathlib import Path

from solver.bounded_read import NOT_REGULAR
from solver.errors import InputError, NotFoundError
from solver.store.errors import StoreBusyError, StoreWriteError

WRITER_SUFFIX = ".lock"
JOB_SUFFIX = ".job.lock"


def database_path(path: str | os.PathLike) -> Path:
    """The file a database path names: a symbolic link (or a chain of them) resolved to
    its target, so that a publish renames over the real file and the locks are the real
    file's; any other path as given (its messages keep the user's words)."""
    path = Path(path)
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def no_database(path: str | os.PathLike, then: str) -> Exception:
    """The error for a database path that names no database file: NotFoundError ("no
    curve database at PATH" + ``then``, what to do) when nothing is there; an InputError
    at ``db`` saying what is there instead -- a directory, a device or a pipe -- where
    "create one there" would be no advice (``balloon fit --db .`` was told to run
    ``balloon precompute GRID.toml --db .``)."""
    path = Path(path)
    if not path.exists():
        return NotFoundError(f"no curve database at {path}{then}")
    return InputError("db", f"{path} is {_what_is_there(path)}, not a curve database",
                      "the path of an HDF5 file written by balloon precompute")


def _what_is_there(path: Path) -> str:
    """What a database path that is no regular file names, in words."""
    return "a directory" if path.is_dir() else NOT_REGULAR


def unwritable(path: str | os.PathLike) -> str | None:
    """Why a put could not publish into the database at ``path``, in words that name the
    file by its name only (a server sends them to clients), or None when it can. A put
    writes a new file beside the database and renames it over (its directory must take
    both) under the sidecar lock ``<db>.lock``; a missing file is created by the first
    put. Checked before work whose result a put must store (the service's solve jobs):
    a directory, a device, a second hard link, a directory that does not exist or takes
    no new file would otherwise fail the put after the work."""
    path = database_path(path)
    name = path.name
    if path.exists() and not path.is_file():
        return f"{name} is {_what_is_there(path)}, not a curve database"
    try:
        names = path.stat().st_nlink
    except FileNotFoundError:
        names = 1
    if names > 1:
        return f"{name} has {names} names (hard links): a write would replace one of them"
    if not path.parent.is_dir():
        return f"the directory of {name} does not exist"
    if not os.access(path.parent, os.W_OK | os.X_OK):
        return f"the directory of {name} takes no new file (read-only or no permission)"
    lock = lock_path(path)
    if lock.exists() and not os.access(lock, os.W_OK):
        return f"its lock file {lock.name} is not writable"
    return None


def refuse_other_names(path: Path) -> None:
    """StoreWriteError when the database file has other names (hard links): a publish
    renames a new file over this name only, so the others would keep the former records
    and their own locks -- two databases where there was one (a symbolic link is followed
    instead, ``database_path``). Nothing is written; a missing file passes."""
    try:
        names = path.stat().st_nlink
    except FileNotFoundError:
        return
    if names > 1:
        raise StoreWriteError(path, OSError(errno.EMLINK, (
            f"it has {names} names (hard links); a write would replace the file under this "
            "name only and the others would keep the former records: copy it to a file of "
            "its own (cp) and write to that")))


def lock_path(db_path: Path, suffix: str = WRITER_SUFFIX) -> Path:
    """The sidecar lock file of ``db_path``: the writer's, or with JOB_SUFFIX the job's."""
    return db_path.with_name(db_path.name + suffix)


def _database_of(lock: Path) -> Path:
    """The database a lock file belongs to: its name less the lock's suffix."""
    for suffix in (JOB_SUFFIX, WRITER_SUFFIX):
        if lock.name.endswith(suffix) and len(lock.name) > len(suffix):
            return lock.with_name(lock.name[:-len(suffix)])
    return lock


def holder_stamp() -> str:
    """What a lock file holds: this process's ``<pid>@<host>``."""
    return f"{os.getpid()}@{socket.gethostname()}"


def _holder(stamp: str) -> tuple[str, str]:
    """A lock file's ``<pid>@<host>`` in words, and what to do about its holder: wait for
    it or stop it; a pid of this host that has ended holds the lock through a process it
    started (which ``fuser`` names)."""
    pid_text, _, host = stamp.partition("@")
    if not pid_text.isdigit():
        return "pid ?", "wait for it to finish or stop it"
    pid = int(pid_text)
    if host and host != socket.gethostname():
        return f"pid {pid} on host {host}", "wait for it to finish or stop it there"
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return f"pid {pid}", ("it has ended, but a process it started holds the lock "
                              "(`fuser -v` on the lock file names it): stop that")
    except PermissionError:
        pass
    return f"pid {pid}", f"wait for it to finish or stop it (kill {pid})"


class WriterLock:
    """Exclusive lock; ``acquire`` waits up to ``timeout_s`` (default: not at all), then
    raises StoreBusyError naming the database and the holder (pid, and host if not this
    one). ``what`` words the message. ``release`` removes the lock file."""

    def __init__(self, path: Path, what: str = "being written by another process") -> None:
        self.path = Path(path)
        self.what = what
        self.database = _database_of(self.path)
        self._fd: int | None = None

    @property
    def held(self) -> bool:
        return self._fd is not None

    def acquire(self, timeout_s: float = 0.0) -> None:
        deadline = time.monotonic() + timeout_s
        while True:
            fd = self._open()
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                if time.monotonic() < deadline:
                    os.close(fd)
                    time.sleep(0.02)
                    continue
                who, advice = _holder(os.read(fd, 256).decode("ascii", "replace").strip())
                os.close(fd)
                raise StoreBusyError(
                    f"{self.database} is {self.what} ({who}): {advice}; a database has a "
                    f"single writer and one precompute job at a time (do not delete "
                    f"{self.path.name}: its holder would write on beside the next)") from None
            if self._still_at_path(fd):
                break
            os.close(fd)  # its holder let go and removed it: lock the file there now
        os.ftruncate(fd, 0)
        os.write(fd, holder_stamp().encode("ascii", "replace"))
        self._fd = fd

    def _open(self) -> int:
        try:
            return os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:  # read-only file system, no permission, disk full
            raise StoreWriteError(self.path, exc) from None

    def _still_at_path(self, fd: int) -> bool:
        """The locked file is the one at the lock's path (not one its last holder
        removed as it let go, between this writer's open and lock)."""
        try:
            here = os.stat(self.path)
        except FileNotFoundError:
            return False
        mine = os.fstat(fd)
        return (here.st_dev, here.st_ino) == (mine.st_dev, mine.st_ino)

    def release(self) -> None:
        """Let go: the lock file removed (if it is still ours), unlocked and closed. Safe
        to call again, also when a Ctrl-C interrupted the first call: the descriptor is
        forgotten before it is closed, so a second release (an outer ``finally``) never
        unlocks a descriptor that is closed or, by then, another file's (it raised
        ``OSError: Bad file descriptor`` from the precompute job's Ctrl-C test under
        load, 2026-12-07)."""
        fd, self._fd = self._fd, None
        if fd is None:
            return
        try:
            if self._still_at_path(fd):  # not another writer's (ours was deleted)
                try:  # removed while held, so that no writer locks it after
                    os.unlink(self.path)
                except OSError:  # a directory that takes no change: it blocks nothing
                    pass
            fcntl.flock(fd, fcntl.LOCK_UN)
        finally:
            os.close(fd)
