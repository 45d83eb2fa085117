"""Repeated runs of one specimen (the ``run`` column): a lab loads each specimen 3 times.
The runs share the specimen's stiffness, so they count as one specimen wherever the
calibration's units are specimens: the held-out folds, the noise floor, the scatter
between specimens, the replicate-shared residual, the k + 2 rule and the standard
errors (docs/measured-data.md, "Runs"). Before, a ``run`` column was an unknown column,
and a lab that named each run a curve had its 3 runs counted as 3 specimens.

The data: the cached FE solve of the paper's L 7.1 / t 0.75 mm design (solver defaults,
tests/data/fe_calibration_curves.npz, tests/fe_calibration_curves.py), read by a pump at
2.5 ul/s every second for 10 s; 2 specimens (3 % scatter of the pressure and of the angle
scale) x 3 runs (0.7 deg and 3 Pa reading noise each).
"""

from __future__ import annotations

import numpy as np
import pytest
from calibration_lab import LOADING, Truth, _pump, truth_curve

from surrogate.calibration import DataError, observations_from_rows, run_calibration
from surrogate.calibration._noise import noise_floor
from surrogate.calibration._residual import specimen_units, systematic_residual

PAPER = ("pdms_1_10", "ecoflex_00_30")


def fe_runs(seed: int, specimens: int = 2, runs: int = 3, run_column: bool = True,
            timed: bool = False) -> list[dict]:
    """Rows of ``specimens`` x ``runs`` of the FE design; without ``run_column`` each run
    is a curve of its own (``s1-r2``), as a lab without the column writes it."""
    rng = np.random.default_rng(seed)
    c = truth_curve(7.1, 0.75, PAPER, Truth())
    t, v, _, reads = _pump(LOADING, 2.5, 1.0)
    idx = np.searchsorted(t, reads - 1e-9)
    out = []
    for s in range(specimens):
        sp, sa = 1.0 + 0.03 * rng.standard_normal(2)
        p, a = sp * np.interp(v, c.volume_ul, c.pressure_pa), sa * np.interp(
            v, c.volume_ul, c.angle_deg)
        for r in range(runs):
            for k, i in enumerate(idx):
                row = {"curve_id": f"s{s + 1}" if run_column else f"s{s + 1}-r{r + 1}",
                       "L_mm": 7.1, "t_mm": 0.75, "body_material": PAPER[0],
                       "membrane_material": PAPER[1],
                       "pressure_pa": round(float(p[i] + 3.0 * rng.standard_normal()), 1),
                       "angle_deg": round(float(a[i] + 0.7 * rng.standard_normal()), 2)}
                if timed:
                    row |= {"time_s": float(reads[k]), "flow_ul_s": 2.5}
                if run_column:
                    row["run"] = r + 1
                out.append(row)
    return out


def test_runs_of_a_specimen_are_curves_of_one_specimen():
    obs = observations_from_rows(fe_runs(1))
    assert obs.n_curves == 6 and obs.n_specimens == 2
    assert obs.curve_ids[:3] == ("s1 run 1", "s1 run 2", "s1 run 3")
    assert list(obs.curve_specimen()) == [0, 0, 0, 1, 1, 1]
    assert specimen_units(obs) == (1, 2)        # was (5, 6): 6 "specimens"
    assert obs.subset(np.array([1, 4])).n_specimens == 2


def test_the_noise_floor_compares_a_run_with_other_specimens_only():
    """The floor is what a new specimen scatters. Counted run with run, the runs of one
    specimen made it their repeatability: over 30 draws its median was 2.53 deg where 60
    independent specimens give 3.33; with the run column 3.17, above the former in 24
    of the 30 draws (2 specimens: one draw is far off either way)."""
    truth = noise_floor(observations_from_rows(fe_runs(99, specimens=60, runs=1))).rms_deg
    runs = np.array([noise_floor(observations_from_rows(fe_runs(s))).rms_deg
                     for s in range(30)])
    as_specimens = np.array([noise_floor(observations_from_rows(
        fe_runs(s, run_column=False))).rms_deg for s in range(30)])
    assert np.median(runs) == pytest.approx(truth, rel=0.1)
    assert np.median(as_specimens) < 0.8 * truth
    assert np.mean(runs > as_specimens) >= 0.75


def test_the_calibration_holds_a_specimen_out_with_all_its_runs():
    """Read against the gauge, the paper's model recalibrated: held out by curve, the
    other runs of the held-out specimen stayed in the fit (cross-validated 1.93 deg);
    held out by specimen 2.38 deg, and the scatter between specimens and the floor are
    the specimens' (seed 1)."""
    as_runs = run_calibration(observations_from_rows(fe_runs(1)), "paper").report
    before = run_calibration(observations_from_rows(fe_runs(1, run_column=False)),
                             "paper").report
    assert as_runs["data"]["n_specimens"] == 2 and before["data"]["n_specimens"] == 6
    assert "by specimen" in as_runs["cross_validation"]["method"]
    assert as_runs["cross_validation"]["folds"] == 2
    assert as_runs["rmse_before_deg"] > 1.15 * before["rmse_before_deg"]
    assert as_runs["noise_floor_deg"] > 1.15 * before["noise_floor_deg"]
    assert (as_runs["specimen_scatter"]["pressure_scale_sd"]
            > 1.15 * before["specimen_scatter"]["pressure_scale_sd"])


def test_two_specimens_leave_the_replicate_shared_residual_untested():
    """Run pairs of two specimens are one pair of specimens: 2 specimens x 3 runs made 9
    pairs and a standard error of 0.037 deg^2 on correlated products."""
    obs = observations_from_rows(fe_runs(1))
    resid = np.random.default_rng(0).standard_normal(obs.n)
    assert systematic_residual(obs, resid) is None
    three = observations_from_rows(fe_runs(1, specimens=3))
    s = systematic_residual(three, np.random.default_rng(0).standard_normal(three.n))
    assert s is not None and s["pairs"] == 3 and s["curves"] == 3


def test_runs_of_one_specimen_alone_are_calibrated_as_replicates_and_said_so():
    """A lab that loads its one actuator three times is answered (until 2026-12-07 it was
    refused: "cross-validation by specimen needs a second specimen"): its runs are taken
    as replicates of each other, as if the file named them as curves, and the report says
    what that means."""
    one = run_calibration(observations_from_rows(fe_runs(1, specimens=1)), "paper").report
    named = run_calibration(observations_from_rows(fe_runs(1, specimens=1,
                                                           run_column=False)), "paper").report
    assert one["data"]["n_specimens"] == 1 and one["data"]["n_curves"] == 3
    assert one["data"]["runs_as_replicates"] and not named["data"]["runs_as_replicates"]
    assert one["cross_validation"]["method"].startswith("grouped K-fold by run")
    said = [w for w in one["warnings"] if "runs of one specimen" in w]
    assert len(said) == 1 and "describes this specimen, not its batch" in said[0]
    assert "\n" not in said[0]
    for key in ("selected_effects", "rmse_before_deg", "rmse_after_deg", "noise_floor_deg"):
        assert one[key] == named[key], key


def test_a_specimen_whose_runs_change_its_design_is_refused():
    data = fe_runs(1)
    for r in data:
        if r["curve_id"] == "s1" and r["run"] == 2:
            r["t_mm"] = 0.5
    with pytest.raises(DataError) as err:
        observations_from_rows(data)
    assert err.value.column == "t_mm" and "specimen 's1'" in str(err.value)


@pytest.mark.parametrize("header", ["run", "Run", "cycle", "Repeat"])
def test_the_run_column_is_named_as_labs_name_it_and_read_alike(header):
    data = [{(header if k == "run" else k): (str(v) if k == "run" else v)
             for k, v in r.items()} for r in fe_runs(1)]
    assert observations_from_rows(data).sha256 == observations_from_rows(fe_runs(1)).sha256


def test_a_missing_run_label_names_its_row():
    data = fe_runs(1)
    data[7]["run"] = ""
    with pytest.raises(DataError) as err:
        observations_from_rows(data)
    assert err.value.column == "run" and err.value.row == 8


def test_http_reads_runs_as_the_cli_does(tmp_path):
    """POST /v1/calibrate: runs of one specimen alone are answered as replicates, said in
    the report (until 2026-12-07 a 422 on rows.curve_id; before that a 500 from a
    cross-validation with one fold); two specimens' runs answer by specimen."""
    from fastapi.testclient import TestClient
    from service_fakes import settings_for

    from service.app import create_app

    app = create_app(settings_for(tmp_path), load_surrogate=False)
    with TestClient(app) as client:
        r = client.post("/v1/calibrate", json={"rows": fe_runs(1, specimens=1),
                                               "model": "paper"})
        assert r.status_code == 200, r.text
        one = r.json()
        assert one["data"]["runs_as_replicates"] and one["data"]["n_specimens"] == 1
        assert "cross-validated by run" in one["interpretation"]
        assert any("runs of one specimen" in w for w in one["warnings"])
        r = client.post("/v1/calibrate", json={"rows": fe_runs(1), "model": "paper"})
    assert r.status_code == 200, r.text
    report = r.json()
    assert report["data"]["n_specimens"] == 2 and report["data"]["n_curves"] == 6
    assert "cross-validated by specimen" in report["interpretation"]
