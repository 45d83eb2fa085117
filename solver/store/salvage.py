"""Salvage: the intact records of a damaged curve database copied to a new file.

A damaged record (a flipped byte in its curve, a design that no longer gives its key) is
refused wherever it is read, so a file holding one cannot be sealed, exported whole or
filled by the precompute job. ``salvage(DB, NEW)`` (``balloon db salvage DB -o NEW.h5``)
reads every record of DB and writes those that read back, unchanged (key, curve,
provenance), into the new database NEW with DB's metadata (its commands, grid and runs)
and ``salvaged_from`` (DB as named, its record count, the keys left out); the damaged
ones are named, not copied. ``balloon precompute`` on NEW then solves their designs
again where its grid has them.

A sealed file whose seal no longer matches (bytes changed anywhere) is read as a file
of older code: a copy without its seal in a temporary directory, walked first in a
guarded child process (``integrity.py``), so damage in HDF5's own structures stalls or
kills that child, never this process.

NEW is written under a staging name beside it and linked to NEW only when complete: a
file another process made at NEW meanwhile (a second salvage, a precompute job) is
refused, never written into or removed (the reading of DB takes seconds a thousand
records, and the first version wrote into such a file or, finding it busy, deleted it).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from solver.errors import InputError, NotFoundError
from solver.store import integrity
from solver.store.errors import DamagedStoreError
from solver.store.hdf5 import CurveStore
from solver.store.locking import database_path, lock_path, no_database
from solver.store.record import Record, utc_now

MANAGED = ("format", "schema_version", "created_utc", "updated_utc", "n_records")


@dataclass
class Salvaged:
    """What ``salvage`` did: records copied, and the keys of those left out (damaged)."""

    source: str
    target: str
    copied: int = 0
    damaged: list[str] = field(default_factory=list)

    @property
    def total(self) -> int:
        return self.copied + len(self.damaged)

    def lines(self) -> list[str]:
        out = [f"salvaged {self.copied} of {self.total} records of {self.source} into "
               f"{self.target}"]
        if self.damaged:
            out.append(f"{len(self.damaged)} damaged, not copied: "
                       + ", ".join(k[:12] for k in self.damaged))
            out.append(f"`balloon precompute GRID.toml --db {self.target}` solves their "
                       "designs again (the grid that made them: `balloon db show "
                       f"{self.target}`)")
        return out


def _seal_broken(path: Path) -> bool:
    """Whether ``path`` carries a seal that no longer matches its bytes."""
    data = path.read_bytes()
    return data.startswith(integrity.MAGIC) and not integrity.is_sealed_image(data)


@contextmanager
def _readable(source: Path) -> Iterator[Path]:
    """``source``, or, when its seal is broken, a copy of it without the seal (read like
    a file of older code: guarded first), deleted afterwards."""
    if not _seal_broken(source):
        yield source
        return
    with tempfile.TemporaryDirectory(prefix="balloon-salvage-") as tmp:
        copy = Path(tmp) / source.name
        data = bytearray(source.read_bytes())
        data[:integrity.USERBLOCK_BYTES] = bytes(integrity.USERBLOCK_BYTES)
        copy.write_bytes(bytes(data))
        yield copy


def _read_intact(db: CurveStore) -> tuple[list[Record], list[str]]:
    """The records of ``db`` that read back, and the keys of those that do not."""
    good, damaged = [], []
    for key in db.keys():
        try:
            good.append(db.get(key))
        except DamagedStoreError:
            damaged.append(key)
        except NotFoundError:
            continue
    return good, damaged


def _metadata(db: CurveStore) -> dict[str, object]:
    """The file's own attributes (commands, grid, runs), or none when they do not read."""
    try:
        meta = db.metadata
    except DamagedStoreError:
        return {}
    return {k: v for k, v in meta.items() if k not in MANAGED}


def salvage(source: str | Path, target: str | Path) -> Salvaged:
    """Copy every record of ``source`` that reads back into the new database ``target``
    (InputError naming ``--output`` when it exists: salvage never writes into a
    database), with the source's metadata and ``salvaged_from``; returns what was copied
    and the damaged keys. InputError naming ``db`` when no record can be read at all
    (HDF5's structures themselves are damaged: only a copy can restore it)."""
    source_path, target_path = database_path(source), Path(target)
    if not source_path.is_file():
        raise no_database(source, ": nothing to salvage")
    if target_path.exists() or target_path.is_symlink():
        raise InputError("--output", f"{target} exists",
                         "the path of a new file: salvage never writes into a database")
    result = Salvaged(str(source), str(target))
    try:
        with _readable(source_path) as readable, CurveStore(readable) as db:
            good, result.damaged = _read_intact(db)
            meta = _metadata(db)
    except DamagedStoreError as exc:
        raise InputError("db", f"no record of {source} can be read ({exc.cause})",
                         "restore it from a copy") from None
    result.copied = len(good)
    origin = {"path": str(source), "n_records": result.total, "damaged": result.damaged,
              "salvaged_utc": utc_now()}
    staging = target_path.with_name(f".{target_path.name}.{os.getpid()}.salvage")
    try:
        with CurveStore(staging, mode="a") as out:
            out.set_metadata(**meta, salvaged_from=origin)
            out.put_many(good)
        os.link(staging, target_path)             # never over a file made meanwhile
    except FileExistsError:
        raise InputError("--output", f"{target} exists (made while the records were "
                         "read)", "the path of a new file: salvage never writes into a "
                         "database") from None
    finally:                                     # no half-made database left behind
        for leftover in (staging, lock_path(staging)):
            leftover.unlink(missing_ok=True)
    return result
