"""Hostile input files of the thirty-seventh session: a grid or a measured-data file was
read whole before any check (``balloon precompute /dev/zero`` grew to 2.7 GB and ended
in a MemoryError traceback; ``balloon calibrate`` likewise, and a 10^6-row file was
parsed whole, 11 s and 1.1 GB, before its row count was refused); a gzip-compressed
data file was told "it looks like UTF-16 without a byte-order mark"."""

from __future__ import annotations

import gzip
import os

import pytest
from test_harden_s30_cli import _one_line_error
from test_store import record_for

import solver.precompute.grid
import surrogate.calibration._data as data
from service.cli import main
from solver.store import CurveStore
from surrogate.calibration import DataError

GRID = ('name = "small"\n[[sweep]]\npairs = [["pdms_1_10", "ecoflex_00_30"]]\n'
        "L_mm = [7.1]\nt_mm = 0.5\n")
CSV = ("curve_id,L_mm,t_mm,body_material,membrane_material,pressure_pa,angle_deg\n"
       + "".join(f"s{c},7.1,0.5,pdms_1_10,ecoflex_00_30,{p},{p / 100 + c}\n"
                 for c in (1, 2) for p in (0, 400, 800, 1200, 1600)))


def test_a_grid_file_past_the_bound_is_refused_before_it_is_read_whole(
        tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(solver.precompute.grid, "MAX_GRID_BYTES", 1000, raising=False)
    grid = tmp_path / "big.toml"
    grid.write_text(GRID + "# padding\n" * 200)        # 2 kB: valid, past the bound
    assert main(["precompute", str(grid), "--db", str(tmp_path / "db.h5"),
                 "--dry-run"]) == 2
    _one_line_error(capsys, "grid:", "larger than", "at most")
    assert not (tmp_path / "db.h5").exists()


def test_a_data_file_past_the_bound_is_refused_before_it_is_read_whole(
        tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(data, "MAX_FILE_BYTES", 300, raising=False)
    path = tmp_path / "lab.csv"
    path.write_text(CSV)                                # ~600 bytes: valid, past the bound
    assert main(["calibrate", str(path), "--model", "paper", "--report",
                 str(tmp_path / "r.json")]) == 2
    _one_line_error(capsys, "file:", "larger than", "at most")
    assert not (tmp_path / "r.json").exists()


def test_rows_past_the_limit_are_refused_while_reading(monkeypatch):
    """The CSV reader stops at the limit's next row (it built all 10^6 rows before)."""
    monkeypatch.setattr(data, "MAX_ROWS", 5)
    with pytest.raises(DataError, match="more than 5 rows") as exc:
        data.read_csv_rows(CSV)
    assert exc.value.allowed == "at most 5"


def test_a_compressed_data_file_is_told_so(tmp_path, capsys):
    path = tmp_path / "lab.csv.gz"
    path.write_bytes(gzip.compress(CSV.encode()))
    assert main(["calibrate", str(path), "--model", "paper", "--report",
                 str(tmp_path / "r.json")]) == 2
    err = _one_line_error(capsys, "gzip-compressed", "gunzip")
    assert "UTF-16" not in err.split("allowed")[0]


@pytest.mark.parametrize("argv, what", [
    (["fit", "--db", "{dir}", "-o", "{tmp}/out.json"], "is a directory"),
    (["db", "ls", "{dir}"], "is a directory"),
    (["db", "show", "/dev/null"], "not a regular file"),
    (["db", "seal", "{dir}"], "is a directory"),
    (["db", "salvage", "{fifo}", "-o", "{tmp}/new.h5"], "not a regular file"),
])
def test_a_database_path_naming_a_directory_or_device_says_what_is_there(
        tmp_path, capsys, argv, what):
    """It was "no curve database at .; create one with `balloon precompute GRID.toml
    --db .`": advice that cannot be followed."""
    (tmp_path / "adir.h5").mkdir()
    os.mkfifo(tmp_path / "fifo.h5")
    names = {"dir": tmp_path / "adir.h5", "fifo": tmp_path / "fifo.h5", "tmp": tmp_path}
    assert main([a.format(**names) for a in argv]) == 2
    err = _one_line_error(capsys, what, "not a curve database",
                          "allowed: the path of an HDF5 file")
    assert "create one" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir.h5", "fifo.h5"]  # nothing new


@pytest.mark.parametrize("where, words", [
    ("L_mm=nan", ("L_mm: nan is not a finite number", "allowed: 0.5 <= L_mm <= 60")),
    ("t_mm=abc", ("t_mm: 'abc' is not a finite number", "allowed: 0.05 <= t_mm <= 5")),
    ("max_angle_deg=inf", ("max_angle_deg: inf is not a finite number",)),
    ("status=done", ("status: got 'done'", "complete | stopped | failed")),
])
def test_a_filter_no_record_can_meet_is_refused(tmp_path, capsys, where, words):
    """``balloon db ls DB --where L_mm=nan`` listed "0 records" and exited 0."""
    with CurveStore(tmp_path / "db.h5", mode="a") as db:
        db.put(record_for(L_mm=7.1))
    for command in ("ls", "export"):
        assert main(["db", command, str(tmp_path / "db.h5"), "--where", where]) == 2
        _one_line_error(capsys, *words)


def test_a_force_target_on_a_model_without_force_is_one_line(capsys):
    assert main(["inverse", "--kind", "force_at_pressure", "--pressure-pa", "1500",
                 "--force-mn", "1", "--model", "paper"]) == 2
    _one_line_error(capsys, "gives no blocked-tip force", "allowed: angle_at_pressure")


def test_predict_with_the_exponential_model_does_not_load_the_emulator(capsys, monkeypatch):
    """`balloon predict --model exponential` loaded the emulator too (12 s and 667 MB
    against 2.7 s for the paper model; the hostile-input audit of this session)."""
    import surrogate.emulator

    loaded = []

    def record(*args, **kwargs):     # a loading failure is kept, not raised: count calls
        loaded.append(args)
        raise RuntimeError("not loaded in this test")

    monkeypatch.setattr(surrogate.emulator, "load_emulator", record)
    assert main(["predict", "--model", "exponential", "--L-mm", "7.1", "--t-mm", "0.5",
                 "--pressures", "1000"]) == 0
    assert "1000" in capsys.readouterr().out
    assert loaded == []


@pytest.mark.parametrize(("command", "name"), [
    (["calibrate", "{path}", "--report", "{tmp}/r.json"], "DATA"),
    (["precompute", "{path}", "--db", "{tmp}/x.h5", "--dry-run"], "GRID.toml"),
])
@pytest.mark.parametrize("kind", ["missing", "directory"])
def test_an_input_file_that_is_not_there_names_its_argument(tmp_path, capsys, command, name,
                                                            kind):
    """`balloon calibrate nothere.csv` said only "nothere.csv: No such file or directory":
    the argument that named it and what it takes are said too."""
    path = tmp_path / "nothere.csv" if kind == "missing" else tmp_path
    argv = [w.format(path=path, tmp=tmp_path) for w in command]
    assert main(argv) == 2
    _one_line_error(capsys, f"{name}: {path}", "(allowed: an existing file")
