"""CurveStore: round trip, queries, schema refusal, single writer, atomic replace."""

import os

import h5py
import numpy as np
import pytest
from test_precompute_fakes import fake_curve

from solver.design import Design
from solver.errors import InputError, NotFoundError
from solver.materials import make_material
from solver.settings import SolverSettings
from solver.store import (
    CurveStore,
    NotACurveStoreError,
    Record,
    SchemaVersionError,
    StoreBusyError,
    StoreWriteError,
    integrity,
    make_record,
    record_key,
)
from solver.store.schema import SCHEMA_VERSION

SETTINGS = SolverSettings(mesh_level=0, element="hex1")


def record_for(L_mm=7.1, t_mm=0.5, status="complete", **design):
    d = Design(L_mm=L_mm, t_mm=t_mm, **design).validated()
    return make_record(d, SETTINGS, fake_curve(d, status=status, reason=f"fake {status}"))


@pytest.fixture
def db_path(tmp_path):
    return tmp_path / "curves.h5"


def assert_same_record(a: Record, b: Record) -> None:
    assert a.key == b.key
    assert a.design == b.design
    assert a.settings == b.settings
    assert a.provenance == b.provenance
    for name in a.curve.ARRAY_FIELDS:
        x, y = getattr(a.curve, name), getattr(b.curve, name)
        np.testing.assert_array_equal(x, y)  # NaN == NaN here; exact, no tolerance
        assert np.asarray(x).dtype.kind == np.asarray(y).dtype.kind
    for name in ("status", "reason", "pressure_maximum_index", "n_dofs", "wall_time_s",
                 "timings_s"):
        assert getattr(a.curve, name) == getattr(b.curve, name)


def test_round_trip_keeps_every_field(db_path):
    custom = make_material("soft", [1.0, -0.5], [2.0, -2.0])   # stable: each mu*alpha > 0
    original = record_for(L_mm=11.1, t_mm=0.75, T_mm=1.5, membrane_material=custom)
    with CurveStore(db_path, mode="a") as db:
        db.put(original)
    with CurveStore(db_path) as db:
        stored = db.get(original.key)
        assert db.keys() == [original.key]
    assert_same_record(original, stored)
    assert stored.design.membrane_material.mu_kpa == (1.0, -0.5)
    assert set(stored.provenance) == {"package_version", "git_commit", "created_utc",
                                      "wall_time_s", "status", "reason", "host"}


def test_file_layout_is_readable_with_plain_h5py(db_path):
    record = record_for()
    with CurveStore(db_path, mode="a") as db:
        db.put(record)
    with h5py.File(db_path, "r") as f:  # what docs/database.md promises
        assert f.attrs["format"] == "balloon-actuator-curves"
        assert f.attrs["schema_version"] == SCHEMA_VERSION
        g = f["records"][record.key]
        assert g["design"].attrs["L_mm"] == 7.1
        assert g["design"].attrs["body_material_id"] == "pdms_1_10"
        np.testing.assert_array_equal(g["curve/angle_deg"][()], record.curve.angle_deg)
        assert g["curve/tip_displacement_mm"].shape == (6, 2)
        assert g["settings"].attrs["element"] == "hex1"
        assert g["provenance"].attrs["status"] == "complete"


def test_get_missing_key_and_missing_file(db_path):
    with pytest.raises(NotFoundError, match="balloon precompute"):
        CurveStore(db_path)
    with CurveStore(db_path, mode="a") as db:
        with pytest.raises(NotFoundError, match="no record 'abc'"):
            db.get("abc")
        assert db.keys() == [] and len(db) == 0


def test_records_and_query_filter(db_path):
    records = [record_for(4.1), record_for(7.1), record_for(7.1, 1.0),
               record_for(11.1, status="failed"),
               record_for(7.1, body_material=make_material("pdms_1_15", [9.417], [3.299]))]
    with CurveStore(db_path, mode="a") as db:
        db.put_many(records[:2])
        for r in records[2:]:
            db.put(r)
    with CurveStore(db_path) as db:
        assert len(db) == 5 and db.metadata["n_records"] == 5
        assert [r.key for r in db.records(status="failed")] == [records[3].key]
        assert len(list(db.records())) == 5
        assert {r.key for r in db.query(L_mm=7.1)} == {records[i].key for i in (1, 2, 4)}
        # 7.1 reached through float arithmetic still matches (1e-9 relative)
        assert len(db.query(L_mm=0.1 + 7.0, t_mm=0.5, body_material="pdms_1_10")) == 1
        assert len(db.query(status="complete", element="hex1", mesh_level=0)) == 4
        assert db.query(L_mm=59.0) == []
        # a length no design may have is refused with its range (it was [] until
        # 2026-12-08, as `db ls --where L_mm=0.1` listed "0 records")
        with pytest.raises(InputError, match=r"0.5 <= L_mm <= 60 \(mm\)"):
            db.query(L_mm=99.0)
        with pytest.raises(InputError, match="unknown query field"):
            db.query(colour="red")
        with pytest.raises(InputError, match="status"):
            list(db.records(status="done"))


def test_newer_schema_is_refused_with_a_clear_message(db_path):
    with CurveStore(db_path, mode="a") as db:
        db.put(record_for())
    with h5py.File(db_path, "r+") as f:
        f.attrs["schema_version"] = SCHEMA_VERSION + 1
    image = bytearray(db_path.read_bytes())
    integrity.seal(memoryview(image))  # as a newer writer would
    db_path.write_bytes(image)
    with pytest.raises(SchemaVersionError, match=f"schema version {SCHEMA_VERSION + 1}.*"
                                                 f"up to {SCHEMA_VERSION}.*upgrade"):
        CurveStore(db_path)
    with pytest.raises(SchemaVersionError):
        CurveStore(db_path, mode="a")


def test_foreign_files_are_refused(tmp_path):
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["x"] = 1
    with pytest.raises(NotACurveStoreError, match="not a curve database"):
        CurveStore(other)
    text = tmp_path / "notes.h5"
    text.write_text("hello")
    with pytest.raises(NotACurveStoreError, match="not a readable HDF5"):
        CurveStore(text)


def test_single_writer_and_read_only_readers(db_path):
    with CurveStore(db_path, mode="a") as writer:
        with pytest.raises(StoreBusyError, match="single writer"):
            CurveStore(db_path, mode="a")
        with CurveStore(db_path) as reader:
            with pytest.raises(InputError, match="read-only"):
                reader.put(record_for())
        writer.put(record_for())
    with CurveStore(db_path, mode="a") as again:  # the lock went with the writer
        assert len(again) == 1
    with pytest.raises(InputError, match="mode"):
        CurveStore(db_path, mode="w")


def test_put_rejects_inconsistent_records(db_path):
    good = record_for()
    with CurveStore(db_path, mode="a") as db:
        with pytest.raises(InputError, match="key"):
            db.put(Record("0" * 32, good.design, good.settings, good.curve, good.provenance))
        short = fake_curve(good.design)
        bad_curve = type(short)(**{**short.__dict__, "angle_deg": short.angle_deg[:3]})
        with pytest.raises(InputError, match="angle_deg"):
            db.put(Record(good.key, good.design, good.settings, bad_curve, {}))
        assert len(db) == 0  # nothing half-stored


def test_put_replaces_a_record_without_growing_the_file(db_path):
    failed = record_for(status="failed")
    with CurveStore(db_path, mode="a") as db:
        for L in (4.1, 5.1, 6.1):
            db.put(record_for(L))
        db.put(failed)
        size = os.path.getsize(db_path)
        for _ in range(5):
            db.put(record_for())  # same key, now complete
        assert db.get(failed.key).curve.status == "complete"
        assert len(db) == 4
        # HDF5 does not free deleted groups: without the repack this grows by 5 records
        assert os.path.getsize(db_path) <= size * 1.05


def test_reader_sees_new_versions_and_keeps_its_snapshot_valid(db_path):
    first = record_for(4.1)
    with CurveStore(db_path, mode="a") as writer, CurveStore(db_path) as reader:
        assert reader.keys() == []
        writer.put(first)
        assert reader.keys() == [first.key]  # re-opened the new version by itself
        handle = reader._h5
        writer.put(record_for(5.1))
        # the old version a reader still has open stays readable after the rename
        assert list(handle["records"]) == [first.key]
        assert len(reader) == 2


def test_metadata_round_trip_and_reserved_names(db_path):
    with CurveStore(db_path, mode="a") as db:
        db.set_metadata(generator_command="balloon precompute g.toml --db x.h5",
                        runs=[{"command": "x", "solved": 3}], note="ok", count=3)
        with pytest.raises(InputError, match="schema_version"):
            db.set_metadata(schema_version=99)
    with CurveStore(db_path) as db:
        meta = db.metadata
    assert meta["generator_command"] == "balloon precompute g.toml --db x.h5"
    assert meta["runs"] == [{"command": "x", "solved": 3}]
    assert (meta["note"], meta["count"], meta["schema_version"]) == ("ok", 3, SCHEMA_VERSION)
    assert meta["created_utc"] <= meta["updated_utc"]


def test_an_overwritten_metadata_value_leaves_no_trace_in_the_file(db_path):
    # HDF5 keeps an overwritten attribute's old bytes in the file's free space: a local
    # path written by a build job must not ship inside the published database
    with CurveStore(db_path, mode="a") as db:
        db.put(record_for())
        db.set_metadata(generator_command="balloon precompute g.toml --db /home/me/scratch.h5")
        db.set_metadata(generator_command="balloon precompute g.toml --db curves.h5")
    data = db_path.read_bytes()
    assert b"/home/me/scratch.h5" not in data
    assert b"--db curves.h5" in data
    with CurveStore(db_path) as db:
        assert len(db) == 1 and db.metadata["generator_command"].endswith("curves.h5")


def test_orphaned_temporary_files_are_removed_by_the_next_writer(db_path):
    with CurveStore(db_path, mode="a") as db:
        db.put(record_for())
    orphan = db_path.with_name(f".{db_path.name}.tmp-999-0")
    orphan.write_bytes(b"half a file")
    with CurveStore(db_path) as reader:  # readers never delete anything
        assert len(reader) == 1
    assert orphan.exists()
    with CurveStore(db_path, mode="a"):
        assert not orphan.exists()


def test_failed_put_leaves_the_published_file_untouched(db_path, monkeypatch):
    with CurveStore(db_path, mode="a") as db:
        db.put(record_for(4.1))
        before = db_path.read_bytes()

        def broken(group, record):
            group.create_dataset("partial", data=[1.0])
            raise OSError("disk full (simulated)")

        monkeypatch.setattr("solver.store.schema.write_record", broken)
        with pytest.raises(StoreWriteError, match="disk full") as caught:
            db.put(record_for(5.1))
        assert str(db_path) in str(caught.value)  # names the path and the cause
    assert db_path.read_bytes() == before
    assert not list(db_path.parent.glob(".*tmp*"))
    with CurveStore(db_path) as db:
        assert db.keys() == [record_key(Design(L_mm=4.1), SETTINGS)]


def test_a_writer_without_a_held_lock_interleaves_with_other_writers(db_path):
    with CurveStore(db_path, mode="a", hold_lock=False) as batch, \
            CurveStore(db_path, mode="a", hold_lock=False, lock_timeout_s=0.1) as short:
        batch.put(record_for(4.1))
        with CurveStore(db_path, mode="a") as other:  # e.g. the service storing a solve
            other.put(record_for(5.1))
            # while ``other`` holds the lock, a put waits lock_timeout_s, then gives up
            with pytest.raises(StoreBusyError, match="single writer"):
                short.put(record_for(6.1))
        batch.put(record_for(6.1))  # sees the other writer's record and keeps it
        assert len(batch) == 3
