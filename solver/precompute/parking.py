"""Finished solves that could not be written to the database (disk full, read-only file
system) are parked, not lost: one small HDF5 file per record, written atomically, and
written into the database first on the next run of the job.

    <db dir>/<db name>.parked/<key>.h5          beside the database when possible,
    ~/.balloon/parked/<db name>-<hash>/<key>.h5  else (a read-only database directory)

A parked file holds one record in the database's own layout (``solver.store.schema``),
checksum included, so a parked record reads back exactly or not at all.
"""

from __future__ import annotations

import hashlib
import os
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


def unpark(db: CurveStore) -> int:
    """Write every parked record of ``db`` (a writer) in one publish, then delete the
    parked files; returns how many. A parked file that does not read back (damaged) is
    left where it is and not counted."""
    files, records = [], []
    for path in parked_files(db.path):
        try:
            with h5py.File(path, "r") as f:
                records.append(schema.read_record(f[path.stem]))
            files.append(path)
        except (OSError, KeyError, ValueError, RuntimeError, TypeError):
            continue
    if not records:
        return 0
    db.put_many(records)  # StoreWriteError when it still cannot be written: files stay
    for path in files:
        path.unlink(missing_ok=True)
    for directory in parking_dirs(db.path):
        try:
            directory.rmdir()  # only when empty
        except OSError:
            pass
    return len(records)
