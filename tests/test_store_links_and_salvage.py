"""The database named through a symbolic link is the link's target (one file, one lock);
a database with a damaged record is not sealed over it, and `balloon db salvage` copies
its intact records to a new file, naming the damaged ones."""

from __future__ import annotations

import os

import numpy as np
import pytest
from test_store import record_for

from service.cli import main
from solver.store import CurveStore, DamagedStoreError, StoreBusyError, integrity
from solver.store.errors import StoreWriteError

LENGTHS_MM = (4.1, 5.1, 7.1, 9.1)


def write_database(path, sealed: bool = True):
    """Four records (L = 4.1, 5.1, 7.1, 9.1 mm) and a generating command; returns them."""
    records = [record_for(L_mm=L) for L in LENGTHS_MM]
    with CurveStore(path, mode="a") as db:
        db.put_many(records)
        db.set_metadata(generator_command="balloon precompute grid.toml --db c.h5")
    if not sealed:  # as older code wrote it (HDF5 reads it the same)
        data = path.read_bytes()
        path.write_bytes(bytes(integrity.USERBLOCK_BYTES) + data[integrity.USERBLOCK_BYTES:])
    return records


def damage_curve(path, record) -> None:
    """Flip one bit of one stored angle of ``record`` (a tiny change of one number: only
    the record's checksum can tell)."""
    data = bytearray(path.read_bytes())
    at = data.find(np.asarray(record.curve.angle_deg, np.float64)[1:].tobytes())
    assert at > 0
    data[at + 3] ^= 0x01
    path.write_bytes(bytes(data))


@pytest.fixture
def damaged(tmp_path):
    """An unsealed database whose second record's curve has one flipped bit."""
    path = tmp_path / "c.h5"
    records = write_database(path, sealed=False)
    damage_curve(path, records[1])
    return path, records


def test_a_database_named_through_a_symlink_is_written_at_its_target(tmp_path):
    (tmp_path / "data").mkdir()
    real, link = tmp_path / "data" / "real.h5", tmp_path / "link.h5"
    with CurveStore(real, mode="a") as db:
        db.put(record_for(L_mm=4.1))
    link.symlink_to("data/real.h5")
    with CurveStore(link, mode="a") as db:
        db.put(record_for(L_mm=5.1))
    assert link.is_symlink() and link.resolve() == real.resolve()
    with CurveStore(real) as db:
        assert len(db) == 2
    # one file, one writer: its locks are the target's, whichever name is given
    with CurveStore(real, mode="a"), pytest.raises(StoreBusyError, match="single writer"):
        CurveStore(link, mode="a")
    with CurveStore(link, mode="a"), pytest.raises(StoreBusyError, match="single writer"):
        CurveStore(real, mode="a")


def test_a_database_with_a_second_hard_link_is_refused_for_writing_and_kept(tmp_path,
                                                                            capsys):
    # a write renames a new file over one name: the other kept the former records and
    # its own locks, two databases where there was one (an audit of the thirty-sixth
    # session; a symbolic link is followed instead)
    first, second = tmp_path / "a.h5", tmp_path / "b.h5"
    with CurveStore(first, mode="a") as db:
        db.put(record_for(L_mm=4.1))
    os.link(first, second)
    with pytest.raises(StoreWriteError, match="2 names"):
        CurveStore(second, mode="a")
    with CurveStore(second) as db:              # reading it is fine
        assert len(db) == 1
    assert main(["db", "seal", str(second)]) != 0
    err = capsys.readouterr().err
    assert "hard links" in err and len(err.strip().splitlines()) == 1
    assert os.stat(first).st_ino == os.stat(second).st_ino   # nothing was split


def test_seal_refuses_a_database_with_a_damaged_record_naming_it(damaged, capsys):
    path, records = damaged
    before = path.read_bytes()
    assert main(["db", "seal", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert f"record {records[1].key[:12]} of {path} is damaged" in err
    assert f"balloon db salvage {path} -o NEW.h5" in err and "rebuild" not in err
    assert path.read_bytes() == before  # no fresh seal over the damaged record
    with CurveStore(path) as db:
        assert list(db.damaged_records()) == [records[1].key]


def test_salvage_copies_every_intact_record_and_names_the_damaged(damaged, tmp_path, capsys):
    path, records = damaged
    new = tmp_path / "new.h5"
    assert main(["db", "salvage", str(path), "-o", str(new)]) == 0
    err = capsys.readouterr().err
    assert f"salvaged 3 of 4 records of {path} into {new}" in err
    assert f"1 damaged, not copied: {records[1].key[:12]}" in err
    assert integrity.is_sealed_image(new.read_bytes())
    with CurveStore(new) as db:
        assert sorted(db.keys()) == sorted(r.key for i, r in enumerate(records) if i != 1)
        assert not db.damaged_records()
        stored = db.get(records[0].key)
        meta = db.metadata
    assert stored.curve.angle_deg.tolist() == records[0].curve.angle_deg.tolist()
    assert stored.provenance == records[0].provenance
    assert meta["generator_command"] == "balloon precompute grid.toml --db c.h5"
    assert meta["salvaged_from"]["damaged"] == [records[1].key]
    assert meta["salvaged_from"]["n_records"] == 4
    # the salvaged file takes a seal; the source stays as it was
    assert main(["db", "seal", str(new)]) == 0


def test_salvage_reads_a_sealed_file_whose_seal_no_longer_matches(tmp_path, capsys):
    path = tmp_path / "c.h5"
    records = write_database(path)
    damage_curve(path, records[2])  # the whole file is refused at once by its seal
    with pytest.raises(DamagedStoreError, match="seal's checksum") as exc:
        CurveStore(path)
    assert f"balloon db salvage {path}" in str(exc.value)
    new = tmp_path / "new.h5"
    assert main(["db", "salvage", str(path), "-o", str(new)]) == 0
    assert f"1 damaged, not copied: {records[2].key[:12]}" in capsys.readouterr().err
    with CurveStore(new) as db:
        assert len(db) == 3 and records[2].key not in db


def test_salvage_never_writes_into_an_existing_file(damaged, tmp_path, capsys):
    path, _ = damaged
    other = tmp_path / "other.h5"
    write_database(other)
    before = other.read_bytes()
    for target in (other, path):
        assert main(["db", "salvage", str(path), "-o", str(target)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "--output" in err, err
    assert other.read_bytes() == before
