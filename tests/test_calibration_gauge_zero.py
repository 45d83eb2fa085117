"""The gauge at rest (surrogate/calibration/_gauge_zero.py): before the pump has put any
volume in, the chamber's pressure is 0 Pa whatever the actuator, so the readings there
read the gauge's zero directly, whatever the specimens' stiffness does to whole curves."""

from __future__ import annotations

import numpy as np

from surrogate.calibration._gauge_zero import LEVEL, MIN_SD_PA, gauge_at_rest, sentence


def _curves(zero_pa: list[float]) -> tuple[np.ndarray, ...]:
    """Each curve: a reading at rest at t = 0 (its gauge at zero_pa), four pumped
    readings whose gauge is off by a specimen's own 7 % stiffness, and a last one back at
    0 ul after withdrawing (not at rest: what the chamber holds then is its history's)."""
    curve, t, v, gauge = [], [], [], []
    for c, z in enumerate(zero_pa):
        scale = 1.0 + 0.07 * (c - 1)
        for k, vol in enumerate([0.0, 2.0, 4.0, 6.0, 3.0, 0.0]):
            curve.append(c)
            t.append(2.0 * k)
            v.append(vol)
            gauge.append(z + scale * 400.0 * vol + (-300.0 if k == 5 else 0.0))
    return np.array(curve), np.array(t), np.array(v), np.array(gauge)


def test_the_readings_at_rest_read_the_gauges_zero_against_the_models():
    """Three curves at rest 56, 57 and 65 Pa above a model that claims 0 Pa (the
    L9 lab set's readings, benchmarks/lab_rig_sets.py): t = 59.3 / (4.9 / sqrt 3) = 21
    against Student's 9.92 (2 dof, 1 % two-sided); against a model whose offset is the
    readings' mean, nothing is said. The specimens' scatter of the pumped readings and a
    curve withdrawn back to 0 ul (its chamber is not at rest) do not enter."""
    curve, t, v, gauge = _curves([56.0, 57.0, 65.0])
    model = 400.0 * v
    rest = gauge_at_rest(curve, v, gauge, model)
    assert rest["curves"] == 3 and np.isclose(rest["mean_pa"], 178.0 / 3.0)
    assert np.isclose(rest["se_pa"], np.std([56.0, 57.0, 65.0], ddof=1) / np.sqrt(3.0))
    assert np.isclose(rest["critical_t"], 9.925, atol=1e-3) and LEVEL == 0.01
    assert rest["off"]
    said = sentence(rest, [])
    assert "+59 +/- 3 Pa" in said and "zero the gauge" in said
    fitted = gauge_at_rest(curve, v, gauge, model + rest["mean_pa"])
    assert not fitted["off"] and sentence(fitted, ["pressure_offset"]) is None


def test_a_zeroed_gauge_and_too_few_curves_say_nothing():
    """Zeros of +-3 Pa (a gauge zeroed before each run) are not off; nor three curves
    that agree to the gauge's last digit at 2 Pa (sd 0: t was infinite, written as
    Infinity, no JSON number, and the zero said to be off); two curves give no spread
    worth a test."""
    curve, t, v, gauge = _curves([-2.0, 3.0, 1.0])
    assert not gauge_at_rest(curve, v, gauge, 400.0 * v)["off"]
    curve, t, v, gauge = _curves([2.0, 2.0, 2.0])
    agree = gauge_at_rest(curve, v, gauge, 400.0 * v)
    assert np.isfinite(agree["t"]) and not agree["off"]
    assert np.isclose(agree["se_pa"], MIN_SD_PA / np.sqrt(3.0))
    two = curve < 2
    assert gauge_at_rest(curve[two], v[two], gauge[two], 400.0 * v[two]) is None


def test_a_lab_whose_gauge_reads_60_pa_high_is_told_so():
    """The L9 lab set (tests/data/lab_gauge_noise_gauge_zero_off.csv, made by
    benchmarks/lab_rig_sets.py --test-data from FE solves of PDMS 1:10 / Ecoflex L 9.3 mm:
    three specimens of 7 % stiffness scatter, a gauge 60 Pa high with a 1.5 % + 2 Pa
    noise), calibrated without its pump column. Before: nothing selected and nothing said
    (the offset fitted over whole curves was -50 +/- 77 Pa: the specimens' mean
    stiffness). Now the report gives the zero at rest and the interpretation says it."""
    from calibration_lab import emulator
    from test_calibration_history import lab_rows

    from surrogate.calibration import run_calibration

    rows, _ = lab_rows("gauge_zero_off")
    report = run_calibration(rows, emulator()).report
    rest = report["gauge_at_rest"]
    assert rest["off"] and rest["curves"] == 3
    assert abs(rest["mean_pa"] - 60.0) < 3.0 * rest["se_pa"] + 3.0   # the zeros' +-3 Pa
    assert "its zero is off" in report["interpretation"]
    assert report["selected_effects"] in ([], ["pressure_offset"])
