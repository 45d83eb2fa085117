"""Whole-file integrity of a published database, checked before HDF5 parses a byte.

HDF5 trusts its own structures: flipped bytes in a B-tree, a heap or an object header
can make the library loop for ever inside C (seen on the root group's attributes) or
crash the process, and no Python timeout can stop a thread stuck there. So a file is
never handed to HDF5 unchecked:

- **sealed** (every file this code publishes): the first ``USERBLOCK_BYTES`` of the file
  are an HDF5 user block (HDF5 skips it; the superblock follows) holding ``MAGIC``
  and the blake2b-256 digest of everything after the user block. A reader recomputes
  it (about 20 ms per 1 MB) and refuses any difference with DamagedStoreError, so a
  damaged sealed file is refused at once, whatever the damage;
- **unsealed** (written before the seal, or by another tool): HDF5 first reads the
  whole file -- the file's attributes, every record's summary and record, as the store
  does -- in a child process (``python -m solver.store.integrity PATH``), which
  reports each record as it goes; a child that stalls for ``STALL_S`` on one step, or
  dies (a crash in HDF5), makes the file DamagedStoreError, and the child is killed.
  A child that finishes means that the same reads in this process end too (a record
  the child found damaged is refused when read, naming the record). The next write
  seals the file (``balloon db seal`` does it at once).

A version found intact, or found to stall or crash HDF5, is remembered by its stamp
(device, inode, mtime, size) for the life of the process, so the many short-lived readers
of the service check each published version once.
"""

from __future__ import annotations

import hashlib
import os
import selectors
import subprocess
import sys
import threading
import time
from pathlib import Path

from solver.store.errors import READ_ERRORS, DamagedStoreError

USERBLOCK_BYTES = 512  # HDF5: a power of two >= 512
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
# HDF5 looks for its signature at byte 0 and after a user block of 512 bytes or a larger
# power of two: every file this store publishes has it at USERBLOCK_BYTES, after its seal
HDF5_SIGNATURE_OFFSETS = (0, *(2**k for k in range(9, 17)))
HDF5_HEAD_BYTES = HDF5_SIGNATURE_OFFSETS[-1] + len(HDF5_SIGNATURE)
MAGIC = b"balloon-curves-seal blake2b-256 "
DIGEST_HEX = 64
START_S = 120.0  # the child's imports (slow on a loaded machine)
STALL_S = 20.0   # one step of the walk (a record takes ~0.1 s on a loaded machine)

Stamp = tuple[int, int, int, int]


def stamp_of(st: os.stat_result) -> Stamp:
    return (st.st_dev, st.st_ino, st.st_mtime_ns, st.st_size)


def _digest(chunks) -> bytes:
    h = hashlib.blake2b(digest_size=DIGEST_HEX // 2)
    for chunk in chunks:
        h.update(chunk)
    return h.hexdigest().encode()


def looks_like_hdf5(head: bytes) -> bool:
    """Whether a file whose first bytes are ``head`` (HDF5_HEAD_BYTES of them, or the
    whole file) is an HDF5 file, sealed or not: its signature where HDF5 looks for it."""
    return any(head[at:at + len(HDF5_SIGNATURE)] == HDF5_SIGNATURE
               for at in HDF5_SIGNATURE_OFFSETS)


def seal(image: memoryview) -> None:
    """Write the seal into the user block of an in-memory HDF5 image (created with
    ``userblock_size=USERBLOCK_BYTES``)."""
    digest = _digest([image[USERBLOCK_BYTES:]])
    head = MAGIC + digest + b"\n"
    image[:USERBLOCK_BYTES] = head + bytes(USERBLOCK_BYTES - len(head))


def _seal_of(head: bytes) -> bytes | None:
    """The digest written in ``head`` (the user block), or None when it holds no seal."""
    if not head.startswith(MAGIC):
        return None
    return head[len(MAGIC):len(MAGIC) + DIGEST_HEX]


def is_sealed_image(data: bytes | memoryview) -> bool:
    """Whether ``data`` (a whole file) carries a seal that matches it."""
    stored = _seal_of(bytes(data[:USERBLOCK_BYTES]))
    return stored is not None and stored == _digest([memoryview(data)[USERBLOCK_BYTES:]])


# versions checked: (path, stamp) -> sealed (intact), or the DamagedStoreError of a guarded
# read that stalled or died (not repeated for every request of the service)
_checked: dict[tuple[str, Stamp], bool | DamagedStoreError] = {}
_walking = threading.Lock()  # one guarded read at a time (concurrent requests wait for it)


def check(path: Path) -> tuple[Stamp, bool]:
    """Check the file at ``path`` before HDF5 opens it: ``(stamp, sealed)`` of what was
    checked; DamagedStoreError when its seal does not match or a guarded read of an
    unsealed file does not finish. A version found intact is not checked again in this
    process (the store publishes every change as a new file, hence a new stamp)."""
    with open(path, "rb") as fh:
        stamp = stamp_of(os.fstat(fh.fileno()))
        known = _checked.get((str(path), stamp))
        if isinstance(known, DamagedStoreError):
            raise DamagedStoreError(known.path, known.cause) from None
        if known is not None:
            return stamp, known
        stored = _seal_of(fh.read(USERBLOCK_BYTES))
        if stored is not None:
            found = _digest(iter(lambda: fh.read(1 << 20), b""))
            if found != stored:
                raise DamagedStoreError(path, "its bytes changed since it was written: the "
                                        "seal's checksum does not match")
            return _remember(path, stamp, True), True
    with _walking:
        known = _checked.get((str(path), stamp))
        if isinstance(known, DamagedStoreError):
            raise DamagedStoreError(known.path, known.cause) from None
        if known is None:
            try:
                walk_guarded(path)
            except DamagedStoreError as exc:
                _remember(path, stamp, exc)
                raise
    return _remember(path, stamp, False), False


def _remember(path: Path, stamp: Stamp, sealed: bool | DamagedStoreError) -> Stamp:
    if len(_checked) > 64:
        _checked.clear()
    _checked[(str(path), stamp)] = sealed
    return stamp


def walk_guarded(path: Path, start_s: float | None = None,
                 stall_s: float | None = None) -> None:
    """Read the whole file in a child process; DamagedStoreError when the child stalls
    (``START_S`` for its start, ``STALL_S`` for each step after) or dies inside HDF5
    (the child is killed)."""
    start_s = START_S if start_s is None else start_s
    stall_s = STALL_S if stall_s is None else stall_s
    cmd = [sys.executable, "-m", "solver.store.integrity", str(path)]
    child = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                             stdin=subprocess.DEVNULL)
    assert child.stdout is not None
    sel = selectors.DefaultSelector()
    sel.register(child.stdout, selectors.EVENT_READ)
    last, wait_s, done, buffer = "its header", start_s, False, b""
    try:
        deadline = time.monotonic() + wait_s
        while not done:
            left = deadline - time.monotonic()
            if left <= 0 or not sel.select(timeout=left):
                raise DamagedStoreError(path, f"HDF5 stalled for {wait_s:.0f} s reading "
                                        f"{last}")
            data = os.read(child.stdout.fileno(), 4096)
            if not data:
                break
            buffer += data
            *lines, buffer = buffer.split(b"\n")
            for line in lines:
                text = line.decode(errors="replace")
                done = done or text == "done"
                last = last if done else text
            deadline, wait_s = time.monotonic() + stall_s, stall_s
        code = child.wait(timeout=stall_s)
    except subprocess.TimeoutExpired:
        raise DamagedStoreError(path, f"HDF5 stalled reading {last}") from None
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
        sel.close()
        child.stdout.close()
    if not done or code != 0:
        raise DamagedStoreError(path, f"HDF5 failed reading {last} (exit code {code})")


def _walk(path: str) -> None:
    """The child's side: every read the store makes, one line per step on stdout."""
    import h5py

    from solver.store import schema

    def say(text: str) -> None:
        sys.stdout.write(text + "\n")
        sys.stdout.flush()

    say("its header")
    try:
        f = h5py.File(path, "r")
    except OSError:
        say("done")  # the parent's own open fails cleanly too
        return
    with f:
        say("its attributes")
        try:
            schema.check_schema(f, path)
            schema.read_attrs(f)
            keys = sorted(f[schema.RECORDS])
        except READ_ERRORS:
            keys = []
        for n, key in enumerate(keys):
            say(f"record {n + 1} of {len(keys)}")
            try:
                group = f[schema.RECORDS][key]
                schema.plain(group.attrs["status"])
                schema.read_summary(group)
                schema.read_record(group)
            except READ_ERRORS:
                pass
    say("done")


if __name__ == "__main__":
    _walk(sys.argv[1])
