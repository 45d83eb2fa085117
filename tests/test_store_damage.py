"""A damaged database (bytes flipped inside it, not only truncated): every read gives the
stored numbers or a DamagedStoreError naming the file (and the record), never a wrong
number or a raw HDF5 error; the CLI prints one line; a failed write names path and cause."""

from __future__ import annotations

import errno
import random
import re

import numpy as np
import pytest
from test_store import SETTINGS, record_for

from service.cli import main
from solver.store import CurveStore, DamagedStoreError, StoreWriteError


@pytest.fixture(scope="module")
def original(tmp_path_factory):
    path = tmp_path_factory.mktemp("db") / "curves.h5"
    with CurveStore(path, mode="a") as db:
        db.put_many([record_for(L_mm=L) for L in (4.1, 5.1, 7.1, 9.1)])
    with CurveStore(path) as db:
        records = {r.key: r for r in db.records()}
    return path.read_bytes(), records


def read_everything(path):
    with CurveStore(path) as db:
        db.metadata  # noqa: B018
        db.summaries()
        return {key: db.get(key) for key in db.statuses()}


def same(a, b) -> bool:
    return (a.design == b.design and a.settings == b.settings
            and a.provenance == b.provenance and a.curve.reason == b.curve.reason
            and all(np.array_equal(getattr(a.curve, n), getattr(b.curve, n), equal_nan=True)
                    for n in a.curve.ARRAY_FIELDS))


def test_flipped_bytes_give_the_stored_numbers_or_a_damaged_store_error(original, tmp_path):
    data, records = original
    damaged = 0
    for seed in range(90):  # (a few flips of other layouts make HDF5 spin in C: not here)
        rng = random.Random(seed)
        b = bytearray(data)
        start = rng.randrange(len(b) - 64)
        for i in range(start, start + rng.choice([1, 4, 16, 64])):
            b[i] ^= 0xFF
        path = tmp_path / "flipped.h5"
        path.write_bytes(bytes(b))
        try:
            found = read_everything(path)
        except DamagedStoreError as exc:
            damaged += 1
            assert "flipped.h5" in str(exc) and "damaged" in str(exc)
            continue
        assert found.keys() == records.keys(), seed
        assert all(same(found[k], records[k]) for k in found), seed  # never a wrong number
    assert damaged >= 20  # the sample does hit the structures and the data


def test_a_flipped_byte_in_a_curve_is_detected_by_the_checksum(original, tmp_path):
    data, records = original
    record = next(iter(records.values()))
    needle = np.asarray(record.curve.angle_deg, np.float64)[1:].tobytes()
    at = data.find(needle)
    assert at > 0
    b = bytearray(data)
    b[at + 3] ^= 0x01  # a tiny change of one angle: silently wrong without a checksum
    path = tmp_path / "curves.h5"
    path.write_bytes(bytes(b))
    with CurveStore(path) as db, pytest.raises(DamagedStoreError, match="checksum") as exc:
        db.get(record.key)
    assert exc.value.record == record.key


def flip_object_header(data: bytes, index: int) -> bytes:
    """Flip 4 bytes inside the ``index``-th HDF5 object header (0: the root group, 1: the
    records group, 2 onwards: the records' groups): its checksum no longer matches."""
    at = [m.start() for m in re.finditer(b"OHDR", data)][index]
    b = bytearray(data)
    for i in range(at + 6, at + 10):
        b[i] ^= 0xFF
    return bytes(b)


@pytest.mark.parametrize("argv", [["db", "ls"], ["db", "show", "--json"], ["db", "export"],
                                  ["db", "show", "KEY"], ["db", "export", "KEY"]])
@pytest.mark.parametrize("header", [0, 2])
def test_the_cli_on_a_damaged_database_prints_one_line(original, tmp_path, capsys, argv,
                                                       header):
    data, records = original
    path = tmp_path / "curves.h5"
    path.write_bytes(flip_object_header(data, header))
    if header == 0 and "KEY" in argv:
        pytest.skip("nothing opens: covered by the cases without a key")
    if header == 2 and argv == ["db", "show", "--json"]:
        pytest.skip("the file's metadata is intact: shown")
    if "KEY" in argv:
        with pytest.raises(DamagedStoreError) as exc:
            read_everything(path)
        argv = [a if a != "KEY" else exc.value.record[:12] for a in argv]
    code = main([*argv[:2], str(path), *argv[2:]])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "curves.h5" in err and "damaged" in err and "Traceback" not in err


def test_precompute_on_a_damaged_database_is_one_line(original, tmp_path, capsys):
    path = tmp_path / "curves.h5"
    path.write_bytes(flip_object_header(original[0], 1))
    grid = tmp_path / "grid.toml"
    grid.write_text('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = 4.1\n')
    assert main(["precompute", str(grid), "--db", str(path), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "damaged" in err and "Traceback" not in err


def test_a_failed_write_names_the_path_and_the_cause(tmp_path, monkeypatch):
    path = tmp_path / "curves.h5"
    with CurveStore(path, mode="a") as db:
        db.put(record_for(L_mm=4.1))
    before = path.read_bytes()

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("solver.store.hdf5._write_file", full)
    with CurveStore(path, mode="a") as db, pytest.raises(StoreWriteError) as exc:
        db.put(record_for(L_mm=5.1))
    assert str(path) in str(exc.value) and "No space left on device" in str(exc.value)
    assert path.read_bytes() == before and SETTINGS.mesh_level == 0
