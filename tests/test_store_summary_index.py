"""The curve database's summary index (solver/store/schema.py): every record's summary row
kept with the file, so that listing the records reads one dataset, not ~40 attributes a
record (16 s for the shipped 2403). It must give exactly the rows read from the records,
follow every publish, be trusted only where the seal proves it current, and leave no
free space behind."""

import io
from pathlib import Path

import h5py
import pytest
from test_store import record_for

from solver.store import CurveStore, integrity, schema

SHIPPED = Path(__file__).resolve().parents[1] / "service" / "data" / "curves.h5"


def rows_from_attributes(path) -> list[dict]:
    """Every record's summary row read from its own attributes (the index not read)."""
    with h5py.File(path, "r") as f:
        group = f[schema.RECORDS]
        return [schema.read_summary(group[k]) for k in sorted(group)]


def index_of(path) -> dict | None:
    with h5py.File(path, "r") as f:
        return schema.read_summary_index(f)


def test_the_index_follows_every_publish_and_gives_the_records_own_rows(tmp_path):
    path = tmp_path / "curves.h5"
    first = [record_for(L_mm=L) for L in (4.1, 5.1, 7.1)]
    with CurveStore(path, mode="a") as db:
        db.put_many(first)
        db.put(record_for(L_mm=9.1, status="failed"))
        # the same design again, another outcome: the record and its row are replaced
        again = record_for(L_mm=5.1, status="failed")
        assert again.key == first[1].key
        db.put(again)
        db.set_metadata(note="metadata rewrites the file (repacked): the index goes along")
    index = index_of(path)
    rows = rows_from_attributes(path)
    assert sorted(index) == [r["key"] for r in rows] and len(rows) == 4
    assert [index[r["key"]] for r in rows] == rows
    assert index[again.key]["status"] == "failed"
    with CurveStore(path) as db:
        assert db.summaries() == rows
        assert db.summaries(status="failed") == [r for r in rows if r["status"] == "failed"]


def test_publishes_leave_no_old_index_behind(tmp_path):
    """Records added one publish at a time leave the file no larger than the same records
    rewritten without free space (``seal`` repacks), but for the index's last chunk: no
    publish's old index is left behind in the file."""
    path = tmp_path / "curves.h5"
    with CurveStore(path, mode="a") as db:
        for i in range(16):
            db.put(record_for(L_mm=4.1 + 0.5 * i))
        grown = path.stat().st_size
        db.seal()
    packed = path.stat().st_size
    assert grown - packed < 2 * schema.INDEX_CHUNK_BYTES, (grown, packed)


def test_an_unsealed_files_records_are_listed_from_themselves(tmp_path):
    """Another tool may edit an unsealed file's records (docs/database.md): its index is
    not read, and the next publish reads every row again."""
    path = tmp_path / "curves.h5"
    records = [record_for(L_mm=L) for L in (4.1, 5.1)]
    with CurveStore(path, mode="a") as db:
        db.put_many(records)
    data = bytearray(path.read_bytes())
    data[:integrity.USERBLOCK_BYTES] = bytes(integrity.USERBLOCK_BYTES)   # unsealed
    path.write_bytes(bytes(data))
    with h5py.File(path, "r+") as f:             # the other tool's edit
        f[schema.RECORDS][records[0].key].attrs["reason"] = "edited by hand"
    assert index_of(path)[records[0].key]["reason"] != "edited by hand"   # stale
    with CurveStore(path) as db:
        assert [r["reason"] for r in db.summaries()] == [
            r["reason"] for r in rows_from_attributes(path)]
        assert "edited by hand" in [r["reason"] for r in db.summaries()]
    with CurveStore(path, mode="a") as db:
        db.put(record_for(L_mm=7.1))             # published sealed, its index read afresh
    assert index_of(path)[records[0].key]["reason"] == "edited by hand"
    with CurveStore(path) as db:
        assert db.summaries() == rows_from_attributes(path)


def test_a_sealed_file_whose_index_names_other_records_is_listed_from_them(tmp_path):
    """An index that does not name exactly the file's records (older code published records
    and sealed the file without updating it) is not used."""
    path = tmp_path / "curves.h5"
    records = [record_for(L_mm=L) for L in (4.1, 5.1, 7.1)]
    with CurveStore(path, mode="a") as db:
        db.put_many(records)
    image = io.BytesIO(path.read_bytes())
    with h5py.File(image, "r+") as f:
        rows = schema.read_summary_index(f)
        rows.pop(records[0].key)
        rows[records[1].key] = {**rows[records[1].key], "status": "wrong"}
        schema.write_summary_index(f, rows)
    integrity.seal(image.getbuffer())
    path.write_bytes(image.getvalue())
    with CurveStore(path) as db:
        assert db.summaries() == rows_from_attributes(path)


@pytest.mark.parametrize("damage", ["not json", "rows under other keys", "a list"])
def test_an_index_that_does_not_read_as_rows_is_none(tmp_path, damage):
    with h5py.File(tmp_path / "x.h5", "w") as f:
        schema.write_summary_index(f, {"a": {"key": "a"}})
        assert schema.read_summary_index(f) == {"a": {"key": "a"}}
        text = {"not json": b"{", "rows under other keys": b'{"a": {"key": "b"}}',
                "a list": b"[]"}[damage]
        f[schema.SUMMARY_INDEX].resize((len(text),))
        f[schema.SUMMARY_INDEX][:] = list(text)
        assert schema.read_summary_index(f) is None


def test_the_shipped_database_carries_its_index():
    """The shipped file is listed from its index (``balloon db seal`` wrote it), and the
    index gives each record's own row (a sample of them; all 2403 take 16 s)."""
    index = index_of(SHIPPED)
    assert index is not None
    with CurveStore(SHIPPED) as db:
        keys = db.keys()
        assert sorted(index) == keys
        with h5py.File(SHIPPED, "r") as f:
            group = f[schema.RECORDS]
            for key in keys[::97]:
                assert index[key] == schema.read_summary(group[key])
        assert db.summaries()[:3] == [index[k] for k in keys[:3]]


def test_rows_come_back_as_the_same_plain_values():
    """A row read back from the index equals one read from attributes in type too (ints
    stay ints, lists stay lists): ``summaries`` is the same either way."""
    row = {"key": "k", "n_steps": 3, "design": {"L_mm": 7.1}, "settings": {"x": [1.0, 2.0]},
           "provenance": {"ok": True}}
    buf = io.BytesIO()
    with h5py.File(buf, "w") as f:
        schema.write_summary_index(f, {"k": row})
        back = schema.read_summary_index(f)["k"]
    assert back == row and type(back["n_steps"]) is int
