"""Explanations that make exactly the readings a selection makes
(surrogate/calibration/_exact_alike.py), and a selected gauge effect read again with the
gauge's zero at rest taken off (surrogate/calibration/_gauge_zero.py).

A gauge reading k x the chamber pressure and a batch of specimens uniformly k x as stiff
make the same readings: the Ogden energy is linear in its moduli, so both layers' mu x k
take the same shape at the same volume at k x the pressure (docs/calibration.md, "Two
observables", the table's last row)."""

from __future__ import annotations

import numpy as np

from surrogate.calibration._exact_alike import exact_alikes, sentence
from surrogate.calibration._gauge_zero import sentence as zero_sentence
from surrogate.calibration._gauge_zero import wants_zeroed_pass
from surrogate.calibration.effects import EFFECTS

GAIN = {"k_pressure": {"value": 0.936, "sd": 0.012, "unit": "-", "effect": "pressure_gain"}}


def test_a_selected_pressure_gain_names_the_uniformly_softer_batch_beside_it():
    """Before, a gain of 0.936 was told to the lab as the sensor's span error alone
    ("calibrate it against a water column"); the batch whose both layers are x 0.936, the
    same readings, was not named (with three curves the two-parameter pair is not even
    fitted as a candidate)."""
    alike = exact_alikes(("pressure_gain",), GAIN, 0.80, 50.0)
    assert len(alike) == 1
    a = alike[0]
    assert set(a["effects"]) == {"membrane_stiffness", "body_stiffness"} and a["exact"]
    for name in ("membrane_mu_scale", "body_mu_scale"):
        assert a["params"][name]["value"] == 0.936 and a["params"][name]["sd"] == 0.012
    assert a["rmse_cv_deg"] == 0.80 and a["paired_z"] == 0.0
    assert EFFECTS["pressure_gain"].measure_directly in a["measure"]
    assert EFFECTS["body_stiffness"].measure_directly in a["measure"]
    said = sentence(["pressure_gain"], alike)
    assert "same readings exactly" in said and "To tell them apart" in said
    words = EFFECTS["pressure_gain"].interpret(GAIN, {})
    assert "6.4 +/- 1.2 % softer" in words and "span error" in words
    assert "water column" not in words


def test_effects_without_an_exact_alike_add_nothing():
    assert exact_alikes(("pressure_offset", "angle_offset"), {}, 1.0, 10.0) == []
    assert sentence(["pressure_offset"], [{"effects": ["camera_gain"]}]) is None


def test_the_zeroed_pass_is_asked_beside_a_zero_that_is_off_unless_the_offset_reads_it():
    """Since 2026-12-08 an empty selection beside a zero found off and a gauge left above
    its floor is read again with the zero taken off too (N53: the gauge's excess over
    whole curves is then said from the zeroed reading, not beside the zero as if
    unexplained); within its floor there is nothing to read again."""
    off = {"curves": 3, "mean_pa": 59.0, "se_pa": 2.0, "t": 35.0, "critical_t": 9.9,
           "off": True}
    assert wants_zeroed_pass(off, ("pressure_gain",))
    assert not wants_zeroed_pass(off, ("pressure_offset",))
    assert not wants_zeroed_pass(off, ())
    assert not wants_zeroed_pass(off, (), {"left": False})
    assert wants_zeroed_pass(off, (), {"left": True})
    assert wants_zeroed_pass(off, ("pressure_offset", "pressure_gain"))
    assert not wants_zeroed_pass({**off, "off": False}, ("pressure_gain",))
    assert not wants_zeroed_pass(None, ("pressure_gain",))
    kept = {**off, "zeroed": {"selected_effects": ["pressure_gain"], "params": {
        "k_pressure": {"value": 0.914, "sd": 0.012, "unit": "-"}}}}
    assert "pressure_gain remains (k_pressure = 0.914 +/- 0.012)" in zero_sentence(
        kept, ["pressure_gain"])
    gone = {**off, "zeroed": {"selected_effects": [], "params": {}}}
    assert "nothing is selected: pressure_gain stood in for the zero" in zero_sentence(
        gone, ["pressure_gain"])


def test_a_soft_batch_read_by_a_gauge_60_pa_high_is_told_both_readings():
    """The N2 lab set (tests/data/lab_gauge_noise_gauge_zero_off_soft_batch.csv, made by
    benchmarks/lab_rig_sets.py --test-data from FE solves of the reversed pair Ecoflex /
    PDMS 1:15, L 11.3 mm: three specimens whose stiffness is x 0.902, 0.916 and 0.909 --
    the batch 9.1 % soft --, a gauge 60 Pa high), calibrated without its pump column.
    Before: pressure_gain 0.936 +/- 0.012 told as the sensor's span error alone, nothing
    indistinguishable. Now the softer batch is named beside it, exactly, with what tells
    them apart, and with the +59 Pa zero at rest taken off the gain is read again: it
    remains, at the batch's softness (0.914 +/- 0.012 for 0.909)."""
    from calibration_lab import emulator
    from test_calibration_history import lab_rows

    from surrogate.calibration import run_calibration

    rows, _ = lab_rows("gauge_zero_off_soft_batch")
    report = run_calibration(rows, emulator()).report
    assert report["selected_effects"] == ["pressure_gain"]
    exact = [a for a in report["indistinguishable"] if a.get("exact")]
    assert exact and set(exact[0]["effects"]) == {"membrane_stiffness", "body_stiffness"}
    assert "same readings exactly" in report["interpretation"]
    rest = report["gauge_at_rest"]
    assert rest["off"] and rest["zeroed"]["selected_effects"] == ["pressure_gain"]
    k = rest["zeroed"]["params"]["k_pressure"]
    assert abs(k["value"] - 0.909) < 3.0 * k["sd"]      # the batch's mean stiffness
    first = report["fitted"]["effects"]["k_pressure"]["value"]
    assert first - k["value"] > 0.01 and np.isfinite(k["sd"])   # the zero's share
    assert "pressure_gain remains" in report["interpretation"]
