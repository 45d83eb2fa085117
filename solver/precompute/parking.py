"""Finished solves that could not be written to the database (disk full, read-only file
system, its writer lock held by another process past the wait) are parked, not lost: one
small HDF5 file per record, written atomically, and written into the database first by
the next write that gets through (the job's next put, or its next run).

    <db dir>/<db name>.parked/<key>.h5          beside the database when possible,
    ~/.balloon/parked/<db name>-<hash>/<key>.h5  else (a read-only database directory)

A parked file holds one record in the database's own layout (``solver.store.schema``),
checksum included, so a parked record reads back exactly or not at all.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Sequence
from pathlib import Path

import h5py

from solver.store import CurveStore, Record, schema
from solver.store.hdf5 import LIBVER


def parking_dirs(db_path: Path) -> list[Path]:
    """Where parked records of ``db_path`` go, in order of preference."""
    db_path = Path(db_path).resolve()
    tag = hashlib.sha256(str(db_path).encode()).hexdigest()[:12]
    return [db_path.with_name(db_path.name + ".parked"),
            Path.home() / ".balloon" / "parked" / f"{db_path.name}-{tag}"]


def park(record: Record, db_path: Path) -> Path:
    """Write ``record`` to the first parking directory that takes it; returns that
    directory. OSError when none does (then the record is lost, and the caller says so)."""
    last: OSError | None = None
    for directory in parking_dirs(db_path):
        tmp = directory / f".{record.key}.h5.tmp-{os.getpid()}"
        try:
            directory.mkdir(parents=True, exist_ok=True)
            with h5py.File(tmp, "w", libver=LIBVER) as f:
                schema.write_record(f.create_group(record.key), record)
            os.replace(tmp, directory / f"{record.key}.h5")
            return directory
        except OSError as exc:
            try:
                tmp.unlink(missing_ok=True)
            except OSError:
                pass
            last = exc
    assert last is not None
    raise last


def parked_files(db_path: Path) -> list[Path]:
    return sorted(p for d in parking_dirs(db_path) if d.is_dir() for p in d.glob("*.h5"))


def unpark(db: CurveStore, also: Sequence[Record] = (),
           lock_timeout_s: float | None = None) -> int:
    """Write every parked record of ``db`` (a writer), and ``also``, in one publish (the
    writer lock waited for up to ``lock_timeout_s``, default the store's), then delete
    the parked files; returns how many parked records were written. A parked file that
    does not read back (damaged) is left where it is and not counted. StoreBusyError or
    StoreWriteError when the database cannot take them: the files stay."""
    files, records = [], []
    for path in parked_files(db.path):
        try:
            with h5py.File(path, "r") as f:
                records.append(schema.read_record(f[path.stem]))
            files.append(path)
        except (OSError, KeyError, ValueError, RuntimeError, TypeError):
            continue
    if not records and not also:
        return 0
    batch = {r.key: r for r in records} | {r.key: r for r in also}  # one record a key
    db.put_many(batch.values(), lock_timeout_s)
    for path in files:
        path.unlink(missing_ok=True)
    for directory in parking_dirs(db.path):
        try:
            directory.rmdir()  # only when empty
        except OSError:
            pass
    return len(records)
