"""``balloon fit``, ``balloon predict`` and ``balloon inverse`` end to end on a small curve
database written through the store API (synthetic curves with the paper's constants,
surrogate/exponential/synthetic_curves.py), so the fitted a must come back as 0.101 deg/mm."""

import hashlib
import json
import shlex

import numpy as np
import pytest

import service.cli as cli
from solver.curve import Curve
from solver.settings import SolverSettings
from solver.store import CurveStore, make_record
from surrogate import load_surrogate
from surrogate.exponential.synthetic_curves import synthetic_curves


@pytest.fixture(autouse=True)
def only_surrogate_commands(monkeypatch):
    # The other subcommands are tested elsewhere; keep this test independent of them.
    monkeypatch.setattr(cli, "COMMAND_MODULES", ("service.commands.fit",
                                                 "service.commands.predict",
                                                 "service.commands.inverse"))


def as_curve(p: np.ndarray, angle: np.ndarray) -> Curve:
    n = len(p)
    return Curve(pressure_pa=p, volume_ul=np.linspace(0, 1, n), time_s=np.linspace(0, 1, n),
                 angle_deg=angle, tip_displacement_mm=np.zeros((n, 2)),
                 max_membrane_stretch=np.ones(n), force_mn=np.full(n, np.nan),
                 newton_iterations=np.zeros(n, dtype=np.int64), residual_norm=np.zeros(n),
                 negative_eigenvalues=np.full(n, -1, dtype=np.int64), status="complete",
                 reason="max_angle_deg reached")


@pytest.fixture
def db(tmp_path):
    path = tmp_path / "curves.h5"
    settings = SolverSettings(mesh_level=0, element="hex1")
    with CurveStore(path, mode="a") as store:
        for c in synthetic_curves(noise_deg=0.2, seed=31):
            store.put(make_record(c.design, settings, as_curve(c.pressure_pa, c.angle_deg)))
    return path


def test_fit_predict_inverse_commands(db, tmp_path, capsys) -> None:
    out = tmp_path / "s.json"
    assert cli.main(["fit", "--db", str(db), "-o", str(out), "--report-dir",
                     str(tmp_path / "rep"), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "pdms_1_10/ecoflex_00_30" in text and "no record holds a force curve" in text
    s = load_surrogate(out)
    assert s.family_fits[0].parameters["exponential"].theta[0] == pytest.approx(0.101, rel=0.01)
    assert s.provenance["database_name"] == db.name     # the name, never the path
    assert str(db.parent) not in json.dumps(s.provenance["database"])
    assert s.provenance["database"]["sha256"] == hashlib.sha256(db.read_bytes()).hexdigest()
    assert s.provenance["fit_command"] == shlex.join(["balloon", "fit", "--db", str(db),
                                                      "-o", str(out)])
    assert len(s.provenance["record_keys"]) == 12
    assert sorted(p.name for p in (tmp_path / "rep").iterdir())[-1] == "report.json"
    assert len(list((tmp_path / "rep").glob("*.png"))) == 2

    assert cli.main(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "0", "1500",
                     "--model", str(out), "--json"]) == 0
    pred = json.loads(capsys.readouterr().out)
    assert pred["angle_deg"][0] == 0.0 and pred["validity"]["in_domain"]

    assert cli.main(["inverse", "--L-mm", "7.1", "--t-mm", "0.5", "--angles-deg",
                     str(pred["angle_deg"][1]), "--model", str(out), "--json"]) == 0
    inv = json.loads(capsys.readouterr().out)
    assert inv["pressure_pa"][0] == pytest.approx(1500.0)

    assert cli.main(["inverse", "--angle-deg", "30", "--pressure-pa", "1500", "--model",
                     str(out)]) == 0
    assert "evaluated designs meet the target" in capsys.readouterr().out


def test_design_search_on_the_default_model_searches_the_box_like_the_api(capsys) -> None:
    """``balloon inverse`` without --angles-deg runs the API's search
    (surrogate.search.design_search) with every bound of POST /v1/inverse. Before, it ran
    the exponential model's own search, and with the default model (the emulator) it ended
    in a traceback."""
    argv = ["inverse", "--kind", "angle_at_pressure", "--angle-deg", "30", "--pressure-pa",
            "1500", "-n", "2", "--L-range", "10", "10", "--membrane-stiffness-range", "0.8",
            "1.2", "--json"]
    assert cli.main(argv) == 0
    body = json.loads(capsys.readouterr().out)
    assert body["feasible"] and body["model"] == "emulator" and len(body["candidates"]) == 2
    for c in body["candidates"]:
        assert c["design"]["L_mm"] == pytest.approx(10.0)
        # angles match in magnitude: a reversed pair (negative angles) is a candidate too
        assert abs(c["value_at_pressure"]) == pytest.approx(30.0, rel=0.011)
    assert cli.main(["inverse", "--kind", "angle_at_pressure", "--angle-deg", "30",
                     "--pressure-pa", "1500", "--T-range", "5", "6"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--T-range" in err and "0.6..2" in err
    # one design's flags do not steer a search: refused, naming the flag that does
    for flags, names in ((["--L-mm", "9"], ("--L-mm", "--L-range")),
                         (["--W-mm", "6"], ("--W-mm", "W = 3 mm")),
                         (["--body-material", "pdms_1_15"], ("--body-material", "--pair"))):
        assert cli.main(["inverse", "--kind", "angle_at_pressure", "--angle-deg", "30",
                         "--pressure-pa", "1500", *flags]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and all(n in err for n in names), err


def test_predict_at_another_width_answers_the_scaled_copy(capsys) -> None:
    """``balloon predict --W-mm`` (like the API's W_mm): every length doubled at W = 6 mm is
    the W = 3 mm design's scaled copy (default body length scaled with W): the same angles,
    8x the volume; a body length off that rule is refused in one line naming the field."""
    small = ["--L-mm", "7.1", "--t-mm", "0.5"]
    big = ["--L-mm", "14.2", "--t-mm", "1.0", "--T-mm", "2", "--b-mm", "3.6", "--h-mm", "0.3",
           "--W-mm", "6"]
    answers = []
    for design in (small, big):
        assert cli.main(["predict", *design, "--pressures", "500", "1500", "--json"]) == 0
        answers.append(json.loads(capsys.readouterr().out))
    assert answers[1]["design"]["body_length_mm"] == pytest.approx(24.0)
    assert answers[1]["angle_deg"] == pytest.approx(answers[0]["angle_deg"], rel=1e-12)
    assert np.allclose(answers[1]["volume_ul"], 8 * np.array(answers[0]["volume_ul"]))
    assert cli.main(["predict", *big, "--body-length-mm", "16", "--pressures", "500"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "body_length_mm" in err and "24" in err


def test_user_mistakes_exit_2_with_one_line(tmp_path, capsys) -> None:
    assert cli.main(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "1",
                     "--body", "pdms_1_15", "--model", "paper"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "balloon precompute" in err
    assert cli.main(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "1",
                     "--model", str(tmp_path / "none.json")]) == 2
    assert cli.main(["inverse", "--angle-deg", "300", "--pressure-pa", "900",
                     "--model", "paper"]) == 1  # infeasible: explained, not an error
    # 300 deg lies past every curve's end (90 deg): said so, not "raise the pressure"
    assert "lies past the FE's range" in capsys.readouterr().out


def test_a_file_that_cannot_be_opened_is_named_with_the_reason(tmp_path, capsys,
                                                               monkeypatch) -> None:
    monkeypatch.setattr(cli, "COMMAND_MODULES", ("service.commands.calibrate",))
    assert cli.main(["calibrate", str(tmp_path / "none.csv"), "--report",
                     str(tmp_path / "rep")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "none.csv: No such file or directory" in err
    assert "Errno" not in err


@pytest.mark.parametrize("argv, names", [
    (["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "100,abc"], "--pressures"),
    (["predict", "--t", "3"], "--t-mm"),                      # ambiguous abbreviation
    (["predict", "--L-mm", "7.1"], "--t-mm"),                 # missing required option
    (["fit", "--db", "x.h5", "-o", "y.json", "--bogus"], "--bogus"),
])
def test_usage_errors_are_one_line(argv, names, capsys) -> None:
    """argparse's own errors are one line too (no usage block), naming the option."""
    with pytest.raises(SystemExit) as exc:
        cli.main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and names in err and "--help" in err


def test_number_lists_take_commas(capsys) -> None:
    """Numbers pasted with commas (``500,1000``) read as with spaces (``500 1000``)."""
    base = ["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--model", "paper", "--json"]
    assert cli.main(base + ["--pressures", "500,1000", "1500"]) == 0
    with_commas = json.loads(capsys.readouterr().out)
    assert cli.main(base + ["--pressures", "500", "1000", "1500"]) == 0
    assert json.loads(capsys.readouterr().out) == with_commas
