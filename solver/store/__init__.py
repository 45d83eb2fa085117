"""The curve database: one HDF5 file of solved curves keyed by design + solver settings.

    from solver.store import CurveStore, Record, record_key, SchemaVersionError
    with CurveStore("curves.h5", mode="a") as db:      # single writer, creates the file
        db.put(make_record(design, settings, curve))
    with CurveStore("curves.h5") as db:                # any number of readers
        db.keys(); db.get(key); db.records(status="complete"); db.query(L_mm=7.1)

Layout: ``solver.store.schema`` and docs/database.md. Publishing (why readers never
see a half-written record, and what survives kill -9): ``solver.store.hdf5``.
Errors: SchemaVersionError, StoreBusyError (a second writer), NotACurveStoreError
(an InputError) and DamagedStoreError (bytes damaged inside the file), StoreWriteError
(disk full, read-only), and NotFoundError for a missing record or file.
"""

from solver.store import integrity
from solver.store.errors import (
    DamagedStoreError,
    NotACurveStoreError,
    SchemaVersionError,
    StoreBusyError,
    StoreWriteError,
)
from solver.store.hdf5 import CurveStore
from solver.store.keys import canonical_json, record_key
from solver.store.record import Record, failed_curve, make_provenance, make_record
from solver.store.schema import SCHEMA_VERSION

__all__ = [
    "SCHEMA_VERSION", "CurveStore", "DamagedStoreError", "NotACurveStoreError", "Record",
    "SchemaVersionError", "StoreBusyError", "StoreWriteError", "canonical_json", "failed_curve",
    "integrity", "make_provenance", "make_record", "record_key",
]
