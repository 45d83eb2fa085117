"""Hostile command lines of the thirtieth session, each one line naming the option and its
range: a design option's text that is not a number (argparse said "invalid float value"
and no range), a design search's bounds reaching past the emulator's box (clipped to it
without a word), `serve --host` that does not resolve (uvicorn's log, after the ~10 s
of loading the models), a saved model's name that is a built-in one in another case or
differs only in case from a saved one; and SIGTERM ending `precompute` with 143."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import pytest

from service.cli import main
from solver.design import LIMITS_MM
from solver.design_space import BOX_MM, STIFFNESS_SCALE_RANGE
from solver.precompute.job import JobSummary


def _one_line_error(capsys, *words: str) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, err
    return err


@pytest.mark.parametrize(("command", "option", "name"), [
    (["solve", "--quiet"], "--L-mm", "L_mm"),
    (["solve", "--quiet"], "--chamber-offset-mm", "chamber_offset_mm"),
    (["predict", "--t-mm", "0.5", "--pressures", "1000"], "--L-mm", "L_mm"),
    (["predict", "--L-mm", "7", "--t-mm", "0.5", "--pressures", "1000"], "--W-mm", "W_mm"),
    (["inverse", "--L-mm", "7", "--angles-deg", "30"], "--t-mm", "t_mm"),
])
def test_a_design_length_that_is_not_a_number_names_the_option_and_its_range(
        capsys, command, option, name):
    lo, hi = LIMITS_MM[name]
    with pytest.raises(SystemExit) as exit_:
        main([*command, option, "abc"])
    assert exit_.value.code == 2
    _one_line_error(capsys, f"argument {option}: 'abc' is not a number",
                    f"allowed: {lo:g} to {hi:g} mm")


def test_a_stiffness_scale_that_is_not_a_number_names_its_range(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["predict", "--L-mm", "7", "--t-mm", "0.5", "--pressures", "1000",
              "--body-stiffness-scale", "x"])
    assert exit_.value.code == 2
    _one_line_error(capsys, "--body-stiffness-scale", "allowed: 0.01 to 100")


@pytest.mark.parametrize(("flag", "name", "bounds"), [
    ("--L-range", "L_mm", ["2", "30"]),      # both ends past the box: was clipped to 4-18
    ("--L-range", "L_mm", ["10", "30"]),
    ("--h-range", "h_mm", ["0.05", "0.2"]),
    ("--body-stiffness-range", "body_stiffness_scale", ["0.3", "1"]),
    ("--L-range", "L_mm", ["nan", "12"]),
])
def test_search_bounds_past_the_box_are_refused_naming_the_flag_and_the_box(
        capsys, monkeypatch, flag, name, bounds):
    monkeypatch.setattr("surrogate.search.design_search.search_designs",
                        lambda *a, **k: pytest.fail("searched a clipped range"))
    lo, hi = BOX_MM.get(name, STIFFNESS_SCALE_RANGE)
    code = main(["inverse", "--angle-deg", "30", "--pressure-pa", "1200", "--model", "paper",
                 flag, *bounds])
    assert code == 2
    _one_line_error(capsys, f"balloon: error: {flag}:", f"LO <= HI within {lo:g}..{hi:g}")


def test_a_search_bound_that_is_not_a_number_states_the_box(capsys):
    with pytest.raises(SystemExit):
        main(["inverse", "--angle-deg", "30", "--pressure-pa", "1200", "--t-range", "a", "1"])
    lo, hi = BOX_MM["t_mm"]
    _one_line_error(capsys, "--t-range", f"allowed: {lo:g} to {hi:g} mm")


def test_serve_with_a_host_that_does_not_resolve_is_one_line_before_loading(
        capsys, monkeypatch):
    monkeypatch.setattr("service.app.create_app",
                        lambda *a, **k: pytest.fail("loaded the models first"))
    start = time.monotonic()
    assert main(["serve", "--host", "no.such.host.invalid", "--port", "8799"]) == 2
    assert time.monotonic() - start < 30      # a DNS failure, not ~10 s of loading
    _one_line_error(capsys, "--host", "no.such.host.invalid", "allowed:")


def test_serve_on_a_port_in_use_is_one_line_naming_the_port(capsys, monkeypatch):
    import socket

    monkeypatch.setattr("service.app.create_app",
                        lambda *a, **k: pytest.fail("loaded the models first"))
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["serve", "--port", str(port)]) == 2
    _one_line_error(capsys, "--port", str(port))


GRID = """
pairs = [["pdms_1_10", "ecoflex_00_30"]]
L_mm = [4.1]
t_mm = 0.5
[settings]
mesh_level = 0
element = "hex1"
"""


def _interrupted_job(send_sigterm: bool):
    """A stand-in for solver.precompute.precompute: stopped by SIGTERM (sent to this
    process while the command's handler is installed) or by Ctrl-C."""
    def fake(*args, **kwargs):
        try:
            if send_sigterm:
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(5)   # the handler raises at once; never reached
            else:
                raise KeyboardInterrupt
        except KeyboardInterrupt:
            return JobSummary(interrupted=True)
        pytest.fail("SIGTERM did not stop the job")
    return fake


@pytest.mark.parametrize(("sigterm", "status"), [(True, 143), (False, 130)])
def test_precompute_stopped_by_sigterm_exits_143_and_by_ctrl_c_130(
        tmp_path, monkeypatch, capsys, sigterm, status):
    grid = tmp_path / "grid.toml"
    grid.write_text(GRID)
    monkeypatch.setattr("solver.precompute.precompute", _interrupted_job(sigterm))
    previous = signal.getsignal(signal.SIGTERM)
    assert main(["precompute", str(grid), "--db", str(tmp_path / "c.h5"),
                 "--no-progress"]) == status
    assert signal.getsignal(signal.SIGTERM) == previous  # the handler is put back


@pytest.mark.parametrize("name", ["Emulator", "PAPER", "Exponential", "fitteD"])
def test_a_built_in_models_name_in_another_case_is_not_a_saved_models(tmp_path, capsys,
                                                                        name):
    data = Path(__file__).resolve().parents[1] / "surrogate/calibration/data/example_lab.csv"
    code = main(["calibrate", str(data), "--report", str(tmp_path / "r.json"), "--model",
                 "paper", "--save", name, "--models-dir", str(tmp_path / "models")])
    assert code == 2
    _one_line_error(capsys, repr(name), "in any case")
    assert not (tmp_path / "r.json").exists()  # refused before the work


def test_a_name_differing_only_in_case_from_a_saved_model_is_refused(tmp_path, capsys):
    models = tmp_path / "models"
    models.mkdir()
    (models / "Lab1.json").write_text("{}")
    data = Path(__file__).resolve().parents[1] / "surrogate/calibration/data/example_lab.csv"
    code = main(["calibrate", str(data), "--report", str(tmp_path / "r.json"), "--model",
                 "paper", "--save", "lab1", "--models-dir", str(models)])
    assert code == 2
    _one_line_error(capsys, "'Lab1' already exists", "'lab1' differs from it only in case")
    assert not (tmp_path / "r.json").exists()
    assert (models / "Lab1.json").read_text() == "{}"   # the saved model is untouched


@pytest.mark.parametrize("command", [
    ["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "1000", "--model", "paper"],
    ["inverse", "--L-mm", "7.1", "--t-mm", "0.5", "--angles-deg", "10", "--model", "paper"],
])
@pytest.mark.parametrize("level", ["0", "1", "nan"])
def test_a_band_level_out_of_range_names_the_option(capsys, command, level):
    assert main([*command, "--level", level]) == 2
    _one_line_error(capsys, "balloon: error: --level:", "0.5 <= level <= 0.999")


def test_a_name_ending_in_a_newline_is_refused_before_the_work(tmp_path, capsys):
    """NAME_PATTERN's ``$`` matches before a final newline: `--save $'lab1\\n'` saved a
    file "lab1\\n.json" beside lab1.json, a model no HTTP request can name."""
    data = Path(__file__).resolve().parents[1] / "surrogate/calibration/data/example_lab.csv"
    code = main(["calibrate", str(data), "--report", str(tmp_path / "r.json"), "--model",
                 "paper", "--save", "lab1\n", "--models-dir", str(tmp_path / "models")])
    assert code == 2
    _one_line_error(capsys, "invalid model name 'lab1\\n'", "letters, digits")
    assert not (tmp_path / "r.json").exists() and not (tmp_path / "models").exists()
