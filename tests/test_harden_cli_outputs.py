"""The CLI's outputs checked before its work, in one line naming the option: a path in a
directory that cannot be written (/proc), a device or pipe the atomic write would have
replaced (`fit -o /dev/full` turned the device into a JSON file), a suffix the writer
cannot produce (a traceback from meshio or matplotlib after a 20 s solve); a full disk
after the checks is one line too; --adaptive is checked before an emulator is fitted
for it; the default body of the widest design (W 30 mm: 120 mm) is valid."""

from __future__ import annotations

import os

import pytest

from service.cli import main
from solver.design import Design


def _one_line_error(capsys, code: int, *words: str) -> str:
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("balloon: error: ") and "Traceback" not in err
    for w in words:
        assert w in err, err
    return err


@pytest.mark.parametrize(("args", "option"), [
    (["--vtk", "shape.txt"], "--vtk"),
    (["--plot", "plot.xyz"], "--plot"),
    (["--csv", "/proc/x"], "--csv"),
    (["--json", "/proc/self/x.json"], "--json"),
])
def test_solve_refuses_an_output_it_cannot_write_before_solving(tmp_path, capsys, args,
                                                                 option, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("solver.stepping.inflate",
                        lambda *a, **k: pytest.fail("solved before checking the outputs"))
    assert main(["solve", "--max-angle-deg", "1", "--quiet", *args]) == 2
    _one_line_error(capsys, 2, option)


def test_an_output_that_is_a_pipe_is_refused_not_replaced(tmp_path, capsys):
    fifo = tmp_path / "fit.json"
    os.mkfifo(fifo)
    assert main(["fit", "--db", str(tmp_path / "none.h5"), "-o", str(fifo)]) == 2
    _one_line_error(capsys, 2, "--output", "not a regular file")
    assert fifo.is_fifo()


def test_calibrate_checks_report_and_plot_first(tmp_path, capsys):
    data = tmp_path / "d.csv"
    data.write_text("curve_id,L_mm,t_mm,body_material,membrane_material,pressure_pa,angle_deg\n"
                    "a,7.1,0.5,pdms_1_10,ecoflex_00_30,0,0\n")
    assert main(["calibrate", str(data), "--report", str(tmp_path / "r.json"),
                 "--plot", str(tmp_path / "p.xyz")]) == 2
    _one_line_error(capsys, 2, "--plot", ".png")
    (tmp_path / "adir").mkdir()
    assert main(["calibrate", str(data), "--report", str(tmp_path / "adir")]) == 2
    _one_line_error(capsys, 2, "--report", "is a directory")


def test_a_full_disk_is_one_line(tmp_path, capsys, monkeypatch):
    import errno

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "out.json"))

    monkeypatch.setattr("service.commands.db.run_export", full)
    assert main(["db", "export", str(tmp_path / "x.h5"), "-o", str(tmp_path / "out.json")]) == 1
    _one_line_error(capsys, 1, "No space left on device", "out.json")


def test_adaptive_count_is_checked_before_any_fit(tmp_path, capsys, monkeypatch):
    grid = tmp_path / "g.toml"
    grid.write_text('[[sweep]]\npairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = [7.1]\n')
    monkeypatch.setattr("surrogate.emulator.fit_emulator",
                        lambda *a, **k: pytest.fail("fitted before checking N"))
    assert main(["precompute", str(grid), "--db", str(tmp_path / "db.h5"), "--adaptive",
                 "-5", "--dry-run"]) == 2
    _one_line_error(capsys, 2, "--adaptive", "1 <= N <= 10000")


def test_the_widest_and_narrowest_default_bodies_are_valid():
    assert Design(W_mm=30.0).validated().body_length_mm == pytest.approx(120.0)
    assert Design(W_mm=0.2, L_mm=0.5, b_mm=0.1).validated().body_length_mm == \
        pytest.approx(0.8)


@pytest.fixture()
def h5_file(tmp_path):
    import h5py

    path = tmp_path / "C.h5"
    with h5py.File(path, "w") as f:
        f.attrs["marker"] = "keep me"
    return path


@pytest.mark.parametrize("argv", [
    ["db", "export", "{db}", "-o", "{db}"],
    ["db", "export", "{db}", "--format", "json", "-o", "{link}"],
    ["db", "export", "{db}", "--where", "L_mm=59", "-o", "{hard}"],
    ["fit", "--db", "{db}", "-o", "{db}"],
    ["solve", "--max-angle-deg", "1", "--quiet", "--csv", "{db}"],
])
def test_an_output_that_is_the_commands_input_or_a_database_is_refused(
        h5_file, tmp_path, capsys, monkeypatch, argv):
    """`db export C.h5 -o C.h5` replaced the database with its CSV and said "exported 2404
    records"; `fit --db C.h5 -o C.h5` and `solve --csv C.h5` did the same (an audit of
    the thirty-fifth session)."""
    (tmp_path / "link.h5").symlink_to(h5_file)
    os.link(h5_file, tmp_path / "hard.h5")
    before = h5_file.read_bytes()
    monkeypatch.setattr("solver.stepping.inflate",
                        lambda *a, **k: pytest.fail("solved before checking the outputs"))
    names = {"db": h5_file, "link": tmp_path / "link.h5", "hard": tmp_path / "hard.h5"}
    assert main([a.format(**names) for a in argv]) == 2
    option = "--csv" if "solve" in argv else "--output"
    _one_line_error(capsys, 2, option)
    assert h5_file.read_bytes() == before


def test_calibrate_will_not_write_its_report_over_the_data(tmp_path, capsys):
    data = tmp_path / "lab.csv"
    text = ("curve_id,L_mm,t_mm,body_material,membrane_material,pressure_pa,angle_deg\n"
            "a,7.1,0.5,pdms_1_10,ecoflex_00_30,0,0\n")
    data.write_text(text)
    assert main(["calibrate", str(data), "--report", str(data)]) == 2
    _one_line_error(capsys, 2, "--report", "the data file")
    assert data.read_text() == text


def test_a_control_character_in_the_users_input_is_shown_escaped_on_one_line(capsys):
    assert main(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--body-material",
                 "pdms\r\x1b[2J", "--pressures", "1000"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "\r" not in err and "\x1b" not in err
    assert "pdms\\r\\x1b[2J" in err


def test_calibrate_checks_its_models_directory_before_the_work(tmp_path, capsys, monkeypatch):
    """`--save ok3 --models-dir /proc/nope` ran the whole calibration and then said
    "/proc/nope: No such file or directory" without the option (an audit of the
    thirty-fifth session)."""
    data = tmp_path / "d.csv"
    data.write_text("curve_id,L_mm,t_mm,body_material,membrane_material,pressure_pa,angle_deg\n"
                    + "".join(f"{c},7.1,0.5,pdms_1_10,ecoflex_00_30,{p},{p / 100}\n"
                              for c in "ab" for p in (0, 500, 1000, 1500)))
    monkeypatch.setattr("surrogate.calibration.run_calibration",
                        lambda *a, **k: pytest.fail("calibrated before checking --models-dir"))
    assert main(["calibrate", str(data), "--report", str(tmp_path / "r.json"), "--save", "ok3",
                 "--models-dir", "/proc/nope"]) == 2
    _one_line_error(capsys, 2, "--models-dir")
