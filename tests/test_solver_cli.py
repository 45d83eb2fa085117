"""``balloon solve``: a real (coarse) FE solve written to every output format, and bad
output paths refused before any solve starts."""

import csv
import json

import meshio
import numpy as np
import pytest

from service.cli import main
from solver.curve import Curve

COARSE = ["--mesh", "0", "--element", "hex1", "--max-angle-deg", "4", "--quiet"]


def test_solve_writes_json_csv_png_and_vtu(tmp_path, capsys):
    out = {k: tmp_path / f"curve.{k}" for k in ("json", "csv", "png", "vtu")}
    rc = main(["solve", "--L-mm", "7.1", "--t-mm", "0.5", *COARSE, "--json", str(out["json"]),
               "--csv", str(out["csv"]), "--plot", str(out["png"]), "--vtk", str(out["vtu"])])
    assert rc == 0
    assert capsys.readouterr().out.startswith("complete")
    # strict JSON (a free tip's force is null, not NaN: strict parsers refused the file)
    data = json.loads(out["json"].read_text(), parse_constant=lambda c: pytest.fail(c))
    curve = data["curve"]
    assert "force_mn" not in curve or all(f is None for f in curve["force_mn"])
    assert data["design"]["L_mm"] == 7.1 and data["settings"]["element"] == "hex1"
    angle = np.array(curve["angle_deg"])
    assert angle[-1] >= 4 and np.all(np.diff(curve["volume_ul"]) > 0)
    assert np.allclose(curve["time_s"], np.array(curve["volume_ul"]) / 2.5)
    with open(out["csv"]) as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(angle)
    assert float(rows[-1]["angle_deg"]) == pytest.approx(angle[-1], rel=1e-6)
    assert out["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    mesh = meshio.read(out["vtu"])
    assert mesh.points.shape[1] == 3 and len(mesh.point_data) > 0 and len(mesh.cells) > 0


@pytest.mark.parametrize("option", ["--json", "--csv", "--plot", "--vtk"])
def test_output_in_a_missing_directory_is_refused_before_solving(tmp_path, capsys, option):
    rc = main(["solve", *COARSE, option, str(tmp_path / "missing" / "out")])
    captured = capsys.readouterr()
    err = captured.err
    assert rc == 2
    assert "points" not in captured.out          # no solve ran (it prints its summary)
    assert option in err and "does not exist" in err
    assert "Traceback" not in err


def _curve(negative, pmax_index):
    n = len(negative)
    p = np.linspace(0.0, 2000.0, n)
    return Curve(pressure_pa=p, volume_ul=p / 100, time_s=p / 250, angle_deg=p / 20,
                 tip_displacement_mm=np.zeros((n, 2)), max_membrane_stretch=np.ones(n),
                 force_mn=np.full(n, np.nan), newton_iterations=np.zeros(n, int),
                 residual_norm=np.zeros(n), negative_eigenvalues=np.array(negative),
                 status="failed", reason="test", pressure_maximum_index=pmax_index)


def test_stability_notes_name_the_first_unstable_step_and_the_pressure_maximum():
    assert _curve([0, 0, 0, 0, 0], -1).stability_notes() == []
    assert _curve([-1, -1, -1], -1).stability_notes() == []          # inertia not computed
    notes = _curve([0, 0, 0, 2, 2], 3).stability_notes()
    assert len(notes) == 2
    assert "from step 3 (p = 1500 Pa, angle = 75.0 deg, 2 negative" in notes[0]
    assert "pressure maximum 1500 Pa at step 3" in notes[1]
