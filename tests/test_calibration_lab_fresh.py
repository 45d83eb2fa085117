"""The calibration loop on the forty-third session's fresh lab sets
(benchmarks/lab_rig_sets.py N6-N13, made from FE solves of designs D11-D13, their truths
fixed before any calibration; tests/data/lab_gauge_noise_*.csv from its ``--test-data``,
read here without the pump's log, as a lab writes them).

* a stiffness-scaled material (``pdms_1_10*1.3``) is a design's material everywhere else
  in the service; the data loader refused it as an unknown material;
* a reading at the pump's start (time 0) had the inlet's R Q added to its gauge: no fluid
  has flowed through the line there, and a fast pump's 2.9 kPa R Q at three such
  readings left the gauge at 3.4 x its floor, so the inlet resistance was not selected;
* a camera whose time stamps are 0.5 s late (outside the catalogue) split the three
  replicates' hold readings three ways (loading, hold, unloading), the noise floor from
  them rose to 3.3 deg and nothing was said; with the histories agreeing, air in the line
  took up the lag while making the gauge worse than the baseline's;
* a body 12 % stiffer than written fits best but the baseline cannot back its size: a
  camera gain was selected in its place;
* a calibration of a scaled body, saved, refused every design (its pairs recorded by
  the data's ids, asked by preset).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_calibration_history import histories_against_the_log, lab_rows

from solver.materials import MATERIALS
from surrogate.calibration import DataError, observations_from_rows


def test_a_stiffness_scaled_material_is_read_as_the_design_states_it():
    """Before: ``body_material: row 1: unknown material 'pdms_1_10*1.3'`` (N6, N8, N11 were
    refused whole). Now the scaled preset is the nominal design's body, its id in the
    designs' canonical spelling; a scale the material's limits refuse is a one-line error
    naming the field."""
    rows, _ = lab_rows("camera_late")
    scaled = [{**r, "body_material": "pdms_1_10*1.30"} for r in rows]
    obs = observations_from_rows(scaled)
    body = obs.design(0).body_material
    assert body.id == "pdms_1_10*1.3"
    assert body.mu_kpa == pytest.approx([1.3 * m for m in MATERIALS["pdms_1_10"].mu_kpa])
    with pytest.raises(DataError) as err:
        observations_from_rows([{**r, "body_material": "pdms_1_10*0"} for r in rows])
    assert err.value.field == "body_material" and "0.01 <= scale <= 100" in str(err.value)


@pytest.mark.parametrize("name", ["camera_late", "leak_slow_pump"])
def test_replicates_that_read_the_pump_running_in_and_out_read_it_stood(name):
    """N13: each frame shows the bend 0.5 s before its stamp, so the hold's first reading
    still rises by half an interval's bend; N11: a leak of 0.08 ul/s per kPa at a pump of
    1.2 ul/s lowers the hold's bend. Before, the three specimens read such a reading as
    loading, hold and unloading (no majority for the vote) and their histories differed
    (N13 at two readings, its floor 3.3 deg; N11's leak was then left 4.4 deg of shared
    residual and nothing selected); now a shared program that one replicate reads running
    in and another out stood there, as the pump's log says."""
    _, wrong = histories_against_the_log(name)
    assert not wrong, wrong


def test_a_camera_late_against_the_pump_is_said_to_be_outside_the_catalogue():
    """Before: nothing selected and "consistent with replicate scatter" (cross-validated
    4.69 deg against a 3.33 deg floor made of the split histories); with the histories
    agreeing, air in the line (C 1.26 +/- 0.10 ul/kPa) was selected while it took the
    gauge from 96 to 119 Pa against an 80 Pa floor. The truth is outside the catalogue:
    nothing is selected and what is left is said to be structured."""
    from calibration_lab import emulator

    from surrogate.calibration import run_calibration

    rows, _ = lab_rows("camera_late")
    report = run_calibration(rows, emulator()).report
    assert report["selected_effects"] == []
    assert report["residual_structured_after"]
    assert report["noise_floor_deg"] < 1.2
    compliance = next(c for c in report["candidates"] if c["effects"] == ["line_compliance"])
    assert any("worse than the baseline's" in w for w in compliance["why_not"])
    assert "No catalogued effect explains it" in report["interpretation"]
    # the outside-catalogue report of tests/test_calibration_loop.py's hysteresis loop
    # (slow since 2026-12-08), checked here in the default suite: what is left, where, and
    # the nearest catalogued set with why it fails
    assert report["unexplained_rms_deg"] > 0.5
    assert report["unexplained_where"] and "outside the catalogue" in report["interpretation"]
    near = report["closest_rejected"]
    assert near is None or (near["why_not"] and "+".join(near["effects"]).split("+")[0]
                            in report["interpretation"])


def test_a_fast_pumps_inlet_resistance_reads_no_flow_at_the_pumps_start():
    """N9: 0.25 m of 0.5 mm bore tubing (R = 128 mu l / (pi d^4) = 163 Pa per ul/s), the
    loading in 3 s at 18 ul/s and the unloading without a hold. Before, the model added
    R Q to the three readings at time 0 (the chamber at rest, the gauge at 0 Pa): R was
    fitted at 148 +/- 1 and left the gauge at 867 Pa against a 254 Pa floor, so nothing
    was selected (gauge 2800 Pa cross-validated). Now R is the truth's within 2 sd."""
    from calibration_lab import emulator

    from surrogate.calibration import run_calibration

    rows, _ = lab_rows("inlet_fast_unload")
    report = run_calibration(rows, emulator()).report
    assert report["selected_effects"] == ["hydraulic_resistance"]
    r = report["fitted"]["effects"]["R_pa_per_ul_s"]
    assert abs(r["value"] - 163.0) < 2 * r["sd"] + 0.02 * 163.0
    assert not report["gauge_left_after"]["left"]
    assert np.isfinite(report["rmse_pressure_after_pa"])


def test_a_set_the_data_prefer_but_the_baseline_cannot_back_is_not_stood_in_for():
    """N8: the body 12 % stiffer than written (its FE solves), three specimens. The body's
    stiffness fits best (1.155 +/- 0.053, 10.6 lower in BIC than the next, cross-validated
    1.90 deg) but is not significant once the baseline's band at the fitted design counts.
    Before, a camera gain of 0.918 +/- 0.022 was selected in its place (the report naming
    the body beside it as the better fit); now nothing is selected, the camera gain is said
    to stand in for the body, and the body is named with its size and the FE solve that
    would decide."""
    from calibration_lab import emulator

    from surrogate.calibration import run_calibration

    rows, _ = lab_rows("body_stiffer")
    report = run_calibration(rows, emulator()).report
    assert report["selected_effects"] == []
    best = report["unbacked_better"]
    assert best["effects"] == ["body_stiffness"]
    body = best["params"]["body_mu_scale"]
    assert abs(body["value"] - 1.12) < 2 * body["sd"]
    gain = next(c for c in report["candidates"] if c["effects"] == ["camera_gain"])
    assert gain["stands_in_for"] == ["body_stiffness"] and not gain["selectable"]
    assert "would stand in for an explanation the baseline cannot judge" in \
        report["interpretation"]


def test_a_slow_leak_on_a_scaled_body_is_found_and_the_calibration_saved(tmp_path):
    """N11 (D11, its body PDMS 1:10 x 1.3): a leak of 0.08 ul/s per kPa at a 1.2 ul/s pump.
    Before, the set was refused (the scaled body); with it read and the histories split,
    nothing was selected and 9.7 deg flagged. Now the leak is the truth's within 2 sd, and
    the saved model answers for the calibrated design: its pairs were recorded as the
    data's ids (pdms_1_10*1.3) and asked by preset (pdms_1_10), so it refused every
    design, the calibrated one too."""
    from calibration_lab import emulator

    from surrogate.calibration import run_calibration
    from surrogate.calibration._saved import load_model, save_model

    rows, _ = lab_rows("leak_slow_pump")
    cal = run_calibration(rows, emulator())
    assert cal.report["selected_effects"] == ["chamber_leak"]
    g = cal.report["fitted"]["effects"]["G_ul_s_per_kpa"]
    assert abs(g["value"] - 0.08) < 2 * g["sd"]
    save_model(cal, "lab43", tmp_path)
    model = load_model("lab43", tmp_path, design_space=emulator)
    design = observations_from_rows(rows).design(0)
    answer = model.predict(design, [2000.0, 3000.0])
    np.testing.assert_allclose(answer.angle_deg,
                               emulator().predict(design, [2000.0, 3000.0]).angle_deg)
