"""CurveStore: the HDF5 curve database with one writer and any number of readers.

Publishing is copy-on-write. A put never touches the published file: the writer
copies it in memory, adds the records there, writes the copy to a hidden temporary
file next to it (``.curves.h5.tmp-<pid>-<n>``), fsyncs it, and ``os.replace``s it over
the published name (an atomic rename on POSIX), then fsyncs the directory. Hence

- a reader sees either the previous or the next version, never a half-written
  record, and needs no lock: a file it already has open stays valid (the old inode
  lives on until it closes it); a reader re-opens the new version on its next call
  (it compares the path's inode/mtime/size with those of the file it has open);
- a writer killed at any moment (kill -9, power loss after the fsync) leaves the
  last published version intact; the orphaned temporary file is removed the next
  time a writer opens the database;
- a failed write (disk full, read-only file system) raises StoreWriteError naming the
  path and the cause; the published file is untouched;
- every published file is sealed: its checksum in the HDF5 user block, checked before
  HDF5 parses a byte of a new version (``integrity.py``; HDF5 can loop for ever or crash
  on flipped bytes), so a damaged file is one DamagedStoreError at once; a file without
  a seal (older code) is read in a guarded child process first;
- damage inside an unsealed file (flipped bytes: HDF5 structures that no longer parse,
  a record whose design or settings no longer give its key, a dataset whose fletcher32
  checksum fails) raises DamagedStoreError naming the record, never a wrong number;
- one writer at a time, enforced by an exclusive flock on ``<db>.lock``: held for the
  writer's lifetime by default, or, with ``hold_lock=False``, only during each put (a
  long batch job then lets other writers, such as the service, interleave their puts);
- a path that is a symbolic link is opened at its target (``locking.database_path``):
  a publish replaces the target, never the link, and the locks are the target's.

The price: a put costs a copy of the whole file (measured in benchmarks/RESULTS.md);
``put_many`` publishes several records for one copy.
"""

from __future__ import annotations

import io
import itertools
import math
import os
import threading
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import h5py

from solver.curve import STATUSES
from solver.design import LIMITS_MM
from solver.errors import InputError, NotFoundError
from solver.settings import SolverSettings
from solver.store import integrity, schema
from solver.store.errors import READ_ERRORS, DamagedStoreError, StoreWriteError, cause_of
from solver.store.locking import (
    WriterLock,
    database_path,
    lock_path,
    no_database,
    refuse_other_names,
)
from solver.store.record import Record, utc_now

MODES = ("r", "a")
QUERY_FIELDS = (*LIMITS_MM, "body_material", "membrane_material", "status",
                *SolverSettings.__dataclass_fields__)
_counter = itertools.count()
# HDF5 1.8 object format: compact link storage in small groups (about half the size of the
# 1.6 format here) and readable by every HDF5 release since 2008.
LIBVER = ("v108", "v108")
USERBLOCK = integrity.USERBLOCK_BYTES  # where the seal lives (solver/store/integrity.py)


def _write_file(path: Path, data: memoryview) -> None:
    """Write ``data`` to a new file and fsync it (plain I/O: failures are OSError)."""
    with open(path, "xb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())


def _fsync_path(path: Path, directory: bool = False) -> None:
    fd = os.open(path, os.O_RDONLY | (os.O_DIRECTORY if directory else 0))
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def check_filter(name: str, value: object) -> None:
    """InputError for a filter no record can meet for want of sense: an unknown field, a
    length that is not a finite number (``balloon db ls --where L_mm=nan`` listed "0
    records") or outside the design's limits (``LIMITS_MM``, which every stored design
    was checked against: ``L_mm=0.1`` and ``L_mm=1e-400`` listed "0 records"), a status
    that is none."""
    if name not in QUERY_FIELDS:
        raise InputError(name, "unknown query field", ", ".join(QUERY_FIELDS))
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if name in LIMITS_MM:
        lo, hi = LIMITS_MM[name]
        if not (number and math.isfinite(value)):  # type: ignore[arg-type]
            problem = "is not a finite number"
        elif not lo <= value <= hi:  # type: ignore[operator]
            problem = "is outside the lengths a design may have"
        else:
            problem = ""
        if problem:
            raise InputError(name, f"{value!r} {problem}", f"{lo:g} <= {name} <= {hi:g} (mm)")
    if number and not math.isfinite(value):  # type: ignore[arg-type]
        raise InputError(name, f"{value!r} is not a finite number", "a finite number")
    if name == "status" and value not in STATUSES:
        raise InputError("status", f"got {value!r}", " | ".join(STATUSES))


def summary_field(row: dict[str, Any], name: str) -> object:
    """A summary's (``CurveStore.summaries``) value of a query field (QUERY_FIELDS)."""
    return {**row["settings"], **row["design"], "status": row["status"]}.get(name)


def _matches(value: object, wanted: object) -> bool:
    if isinstance(wanted, (int, float)) and not isinstance(wanted, bool):
        return isinstance(value, (int, float)) and math.isclose(
            float(value), float(wanted), rel_tol=1e-9, abs_tol=1e-12)
    return value == wanted


class CurveStore:
    """``CurveStore(path, mode="r")`` reads; ``mode="a"`` writes (creating the file).

    Readers need the file to exist (NotFoundError otherwise); a newer schema raises
    SchemaVersionError. A writer holds the single-writer lock from opening to closing
    (another writer gets StoreBusyError at once); with ``hold_lock=False`` it takes the
    lock only for each put, waiting up to ``lock_timeout_s`` for it. A symbolic link is
    followed to the file it names (``path`` is then the target's). Use as a context
    manager, or call ``close()``. Safe to share between threads.
    """

    def __init__(self, path: str | os.PathLike, mode: str = "r", hold_lock: bool = True,
                 lock_timeout_s: float = 60.0) -> None:
        if mode not in MODES:
            raise InputError("mode", f"got {mode!r}", "r (read) | a (write, create if missing)")
        self.path = database_path(path)
        self.mode = mode
        self.hold_lock = hold_lock
        self.lock_timeout_s = lock_timeout_s
        self._h5: h5py.File | None = None
        self._stamp: tuple[int, ...] | None = None
        self._sealed = False      # the open version carries a seal that matched
        self._mutex = threading.RLock()
        self._lock: WriterLock | None = None
        self._closed = False
        if mode == "a":
            self._lock = WriterLock(lock_path(self.path))
            if hold_lock:
                self._lock.acquire()
        try:
            if mode == "a":
                refuse_other_names(self.path)
                with self._locked():
                    self._remove_orphans()  # before the first put, ``_file`` reads
                    if not self.path.exists():
                        self._publish(lambda f: None, create=True)
            elif not self.path.is_file():   # named as given: a link's target is no input
                raise no_database(path, f"; create one with `balloon precompute GRID.toml "
                                  f"--db {path}`")
            self._file()
        except BaseException:
            self.close()
            raise

    # -- lifecycle -------------------------------------------------------------------------
    def __enter__(self) -> CurveStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        with self._mutex:
            self._closed = True
            if self._h5 is not None:
                self._h5.close()
                self._h5 = None
            if self._lock is not None:
                self._lock.release()
                self._lock = None

    @contextmanager
    def _locked(self, timeout_s: float | None = None) -> Iterator[None]:
        """The writer lock for one change, waited for up to ``timeout_s`` (default:
        ``lock_timeout_s``); a no-op when held for the writer's lifetime."""
        if self._lock is None or self._lock.held:
            yield
            return
        self._lock.acquire(timeout_s=self.lock_timeout_s if timeout_s is None else timeout_s)
        try:
            yield
        finally:
            self._lock.release()

    def __repr__(self) -> str:
        return f"CurveStore({str(self.path)!r}, mode={self.mode!r})"

    @contextmanager
    def _reading(self, record: str | None = None) -> Iterator[None]:
        """HDF5 failures inside the file become DamagedStoreError (naming ``record``);
        the project's own errors (a missing record: NotFoundError) pass unchanged.
        A design or settings attribute that no longer validates is damage too."""
        try:
            yield
        except (schema.NotACurveStoreError, NotFoundError, schema.SchemaVersionError):
            raise
        except READ_ERRORS as exc:
            raise DamagedStoreError(self.path, cause_of(exc, self.path), record) from None

    # -- reading ---------------------------------------------------------------------------
    def _file(self) -> h5py.File:
        """The latest published version, re-opened when the path points to a new file.
        A new version is checked before HDF5 reads it (``integrity.check``: its seal, or
        a guarded read in a child process), and opened only if it is still the file that
        was checked."""
        for _ in range(100):  # a new version published between the check and the open
            try:
                stamp = integrity.stamp_of(os.stat(self.path))
            except FileNotFoundError:
                raise NotFoundError(f"curve database {self.path} has disappeared") from None
            if self._h5 is not None and stamp == self._stamp:
                return self._h5
            if self._h5 is not None:
                self._h5.close()
                self._h5 = None
            try:
                checked, sealed = integrity.check(self.path)
                f = h5py.File(self.path, "r")
            except FileNotFoundError:
                continue
            except OSError as exc:
                raise schema.NotACurveStoreError(
                    "db", f"{self.path} is not a readable HDF5 file "
                    f"({cause_of(exc, self.path)})", "a file written by balloon precompute"
                ) from None
            try:
                if integrity.stamp_of(os.stat(self.path)) != checked:
                    continue
                with self._reading():
                    schema.check_schema(f, self.path)
                    f[schema.RECORDS]  # noqa: B018 - the index must open
            except BaseException:
                f.close()
                raise
            self._h5, self._stamp, self._sealed = f, checked, sealed
            return f
        raise StoreWriteError(self.path, OSError("the file changes faster than it can be read"))

    def _records_group(self) -> h5py.Group:
        return self._file()[schema.RECORDS]

    @property
    def metadata(self) -> dict[str, Any]:
        """File attributes: format, schema_version, created_utc, updated_utc, n_records,
        and what writers added (generator_command, runs, ...)."""
        with self._mutex, self._reading():
            return schema.read_attrs(self._file())

    def keys(self) -> list[str]:
        with self._mutex, self._reading():
            return sorted(self._records_group().keys())

    def __contains__(self, key: object) -> bool:
        with self._mutex, self._reading():
            return isinstance(key, str) and key in self._records_group()

    def __len__(self) -> int:
        with self._mutex, self._reading():
            return len(self._records_group())

    def get(self, key: str) -> Record:
        """The record with this key; NotFoundError when absent."""
        with self._mutex, self._reading(key):
            group = self._records_group()
            if key not in group:
                raise NotFoundError(f"no record {key!r} in {self.path}; `balloon db ls "
                                    f"{self.path}` lists the keys")
            return schema.read_record(group[key])

    def statuses(self) -> dict[str, str]:
        """key -> curve status for every record, without loading any curve."""
        with self._mutex, self._reading():
            group = self._records_group()
            out = {}
            for k in sorted(group):
                with self._reading(k):
                    out[k] = str(schema.plain(group[k].attrs["status"]))
            return out

    def summaries(self, **filters: object) -> list[dict[str, Any]]:
        """Per record: key, status, reason, design (flat, material ids), settings, n_steps,
        provenance -- without loading the curves; ``filters`` as for ``query``."""
        for name, value in filters.items():
            check_filter(name, value)
        with self._mutex, self._reading():
            f = self._file()       # once: the records and the index of the same version
            group = f[schema.RECORDS]
            keys = sorted(group)
            # the index of a sealed file only: the seal proves it is the one published with
            # these records (another tool may have edited an unsealed file's records)
            index = schema.read_summary_index(f) if self._sealed else None
            if index is not None and sorted(index) == keys:
                rows = [index[k] for k in keys]
            else:                      # no index, or one that names other records
                rows = []
                for k in keys:
                    with self._reading(k):
                        rows.append(schema.read_summary(group[k]))
        return [row for row in rows
                if all(_matches(summary_field(row, k), v) for k, v in filters.items())]

    def records(self, status: str | None = None) -> Iterator[Record]:
        """Every record (in key order), optionally only those with ``status``."""
        if status is not None and status not in STATUSES:
            raise InputError("status", f"got {status!r}", " | ".join(STATUSES))
        for key, found in self.statuses().items():
            if status is None or found == status:
                try:
                    yield self.get(key)
                except NotFoundError:
                    continue  # only if a record vanished between two published versions

    def damaged_records(self) -> dict[str, str]:
        """key -> why, for every record that does not read back (its checksum, its key,
        HDF5 inside it): each record is read in full, about 5 ms a record (11 s for the
        shipped 2403). Empty when every record is intact."""
        with self._mutex, self._reading():
            group = self._records_group()
            damaged = {}
            for key in sorted(group):
                try:
                    schema.read_record(group[key])
                except READ_ERRORS as exc:
                    damaged[key] = cause_of(exc, self.path)
            return damaged

    def require_intact(self) -> None:
        """Nothing when every record reads back; else DamagedStoreError naming each
        damaged record (and, as every such error, `balloon db salvage`)."""
        damaged = self.damaged_records()
        if damaged:
            raise DamagedStoreError(self.path, next(iter(damaged.values())),
                                    records=list(damaged))

    def query(self, **filters: object) -> list[Record]:
        """Records whose design, settings or status equal ``filters`` (numbers to 1e-9
        relative), e.g. ``query(L_mm=7.1, body_material="pdms_1_10", status="complete")``."""
        return [self.get(str(row["key"])) for row in self.summaries(**filters)]

    # -- writing ---------------------------------------------------------------------------
    def put(self, record: Record, lock_timeout_s: float | None = None) -> None:
        """Store (or replace) one record, atomically; writer only. ``lock_timeout_s``: as
        for ``put_many``."""
        self.put_many([record], lock_timeout_s)

    def put_many(self, records: Iterable[Record], lock_timeout_s: float | None = None) -> None:
        """Store (or replace) several records in one atomic publish; writer only. Without
        the lock held, it is waited for up to ``lock_timeout_s`` (default: the store's),
        then StoreBusyError."""
        batch = list(records)
        for record in batch:
            schema.validate_record(record)

        def add(f: h5py.File) -> None:
            group = f[schema.RECORDS]
            for record in batch:
                schema.write_record(group.create_group(record.key), record)

        with self._mutex:
            self._require_writer()
            with self._locked(lock_timeout_s):
                existing = self._records_group()  # the latest version, read under the lock
                replaced = {r.key for r in batch if r.key in existing}
                self._publish(add, drop=replaced, changed={r.key for r in batch})

    def set_metadata(self, **items: object) -> None:
        """Add or overwrite file attributes (str, numbers, or JSON-able lists and dicts)."""
        reserved = {"format", "schema_version", "created_utc", "n_records"} & set(items)
        if reserved:
            raise InputError(sorted(reserved)[0], "is managed by the store", "other names")
        with self._mutex:
            self._require_writer()
            with self._locked():
                # rewritten, not patched: HDF5 leaves an overwritten attribute's old value
                # in the file's free space, and a stale value (a local path, say) must not
                # ship inside a published file
                self._publish(lambda f: schema.write_attrs(f, items), repack=True)

    def seal(self) -> None:
        """Publish the file again, rewritten and with its seal (solver/store/integrity.py):
        what a file of older code needs once; the records are unchanged, the free space
        left by earlier edits is gone. Every record is read first: a file with a record
        that does not read back is refused (DamagedStoreError naming them, the file
        unchanged), since a fresh seal would vouch for it; `balloon db salvage` copies
        the intact records instead."""
        with self._mutex:
            self._require_writer()
            with self._locked():
                self._publish(lambda f: None, repack=True, verify=True)

    def _require_writer(self) -> None:
        if self.mode != "a" or self._closed:
            raise InputError("mode", f"{self!r} is read-only (or closed)", "open with mode='a'")

    def _tmp_path(self) -> Path:
        return self.path.with_name(f".{self.path.name}.tmp-{os.getpid()}-{next(_counter)}")

    def _remove_orphans(self) -> None:
        """Temporary files left by a writer that was killed mid-put (we hold the lock)."""
        for orphan in self.path.parent.glob(f".{self.path.name}.tmp-*"):
            try:
                orphan.unlink(missing_ok=True)
            except OSError as exc:  # a read-only file system
                raise StoreWriteError(self.path, exc) from None

    def _publish(self, change: Any, create: bool = False,
                 drop: frozenset[str] | set[str] = frozenset(), repack: bool = False,
                 changed: frozenset[str] | set[str] = frozenset(),
                 verify: bool = False) -> None:
        """Copy the file (rewritten record by record when records are dropped or when it
        is not sealed), apply ``change(h5file)`` to the copy and bring its summary index
        up to date (``changed``: the records ``change`` wrote; schema.py), rewrite the
        result when ``repack`` (no freed bytes survive), fsync, rename over. Called with
        the writer lock held.

        The published copy is sealed, and a seal vouches for every record in it: the
        records of an unsealed source (older code, another tool) are read back first --
        and of any source when ``verify`` -- and a record that does not read back
        refuses the publish (DamagedStoreError naming it, the file unchanged; `balloon db
        salvage` copies the intact ones). A sealed source's records are what this code
        published: its seal was checked when it was opened.

        The copy is built in memory and written to disk with plain file I/O: a failed
        write (disk full, read-only) is then one clean OSError, where HDF5 writing to a
        full disk leaves file handles it can neither flush nor close (and may crash the
        process at exit)."""
        if not create:
            refuse_other_names(self.path)
        self._remove_orphans()
        image = io.BytesIO()
        sealed = True     # the source is what this code published: its index is current
        if create:
            with h5py.File(image, "w", libver=LIBVER, userblock_size=USERBLOCK) as f:
                schema.init_file(f, utc_now())
        else:
            with self._reading():
                published = self.path.read_bytes()
            sealed = integrity.is_sealed_image(published)
            if verify or not sealed:
                self.require_intact()     # about 5 ms a record; once per unsealed file
            if drop or not sealed:
                self._repack(image, drop)  # an unsealed file: read through the check
            else:
                image.write(published)
        tmp = self._tmp_path()
        try:
            with h5py.File(image, "r+", libver=LIBVER) as f:
                change(f)
                # an unsealed source's records may have been edited by another tool:
                # its index is not trusted, every row read again
                schema.update_summary_index(f, changed, keep=sealed)
                f.attrs["updated_utc"] = utc_now()
                f.attrs["n_records"] = len(f[schema.RECORDS])
            if repack:
                with h5py.File(image, "r", libver=LIBVER) as f:
                    image = io.BytesIO()
                    _copy_file(f, image, frozenset())
            integrity.seal(image.getbuffer())
            _write_file(tmp, image.getbuffer())
            os.replace(tmp, self.path)
            _fsync_path(self.path.parent, directory=True)
        except OSError as exc:  # disk full, read-only, no permission
            tmp.unlink(missing_ok=True)
            raise StoreWriteError(self.path, exc) from None
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

    def _repack(self, tmp: Any, drop: frozenset[str] | set[str]) -> None:
        """A fresh copy without the records in ``drop`` (HDF5 does not reclaim the space of
        deleted groups, so replaced records are dropped by rewriting the file)."""
        with self._reading():
            src = self._file()
        _copy_file(src, tmp, drop)


def _copy_file(src: h5py.File, dst_image: Any, drop: frozenset[str] | set[str]) -> None:
    """Write the attributes and the records of ``src`` (less those in ``drop``) into a
    fresh file at ``dst_image``: a copy holds no free space and no stale bytes."""
    with h5py.File(dst_image, "w", libver=LIBVER, userblock_size=USERBLOCK) as dst:
        for name, value in src.attrs.items():
            dst.attrs[name] = value
        group = dst.create_group(schema.RECORDS)
        for key in src[schema.RECORDS]:
            if key not in drop:
                src.copy(src[schema.RECORDS][key], group, name=key)
        if schema.SUMMARY_INDEX in src:    # rows of dropped records: pruned by the publish
            src.copy(src[schema.SUMMARY_INDEX], dst, name=schema.SUMMARY_INDEX)
