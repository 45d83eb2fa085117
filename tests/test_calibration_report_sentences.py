"""What the calibration report says of the pump's fitted switch times and of a gauge left
above its floor (surrogate/calibration/_loop.py: ``_pump_sentence``, ``_gauge_left``).

Found by an independent check on ten lab sets made from FE records (2026-12-05): 8 of 10
reports told the lab that its pump changed state between readings and to reprogram it --
the pump switched on readings; the shifts were 0.00 +- 0.05, or sat at the fit's bound
soaking up an air bubble's misfit -- and quoted the joint angle-and-gauge error next to
the angle's. And a misfit of the gauge pressure alone (53.5 Pa against a 38.7 Pa floor)
was reported as "consistent with replicate scatter"."""

from __future__ import annotations

from surrogate.calibration._augmented_model import SWITCH_BOUND
from surrogate.calibration._loop import _gauge_left, _gauge_sentence, _pump_sentence


def pump(*shifts: tuple[float, float | None]) -> dict:
    return {"open": True, "rmse_cv_without_deg": 1.09, "rmse_cv_with_deg": 1.08,
            "rmse_cv_angle_without_deg": 0.70, "rmse_cv_angle_with_deg": 0.67,
            "shifts": [{"switch": f"c{i}", "shift_reading_intervals": x, "sd": sd}
                       for i, (x, sd) in enumerate(shifts)]}


def test_shifts_within_their_sd_are_no_sign_of_a_pump_switch():
    text = _pump_sentence(pump((0.01, 0.05), (-0.03, 0.04), (0.0, None)))
    assert "no sign that the pump changed state" in text
    assert "Program the pump" not in text


def test_shifts_clear_of_their_sd_are_a_pump_switch_with_the_angles_own_errors():
    text = _pump_sentence(pump((-0.4, 0.05), (0.6, 0.08)))
    assert "The pump changed state between readings (2 of 2" in text
    assert "Program the pump" in text
    assert "0.70 deg, with them 0.67 deg" in text and "1.09" not in text


def test_shifts_at_the_bound_are_named_a_misfit_not_a_timing():
    # an air bubble's set: two at the bound, two clear of their sd taking up the same
    text = _pump_sentence(pump((-SWITCH_BOUND, 0.016), (0.08, 0.014),
                               (-0.737, 0.013), (0.14, 0.011)))
    assert "2 sit at the fit's bound" in text and "not a pump timing" in text
    assert "changed state between readings" not in text and "Program the pump" not in text


def test_a_gauge_left_above_its_floor_is_said():
    channel = {"pressure_floor_pa": 38.7}
    gauge = _gauge_left(53.5, channel, 1.12)
    assert gauge["left"] and gauge["limit"] == 1.3
    assert "53 Pa RMS" in _gauge_sentence(gauge) or "54 Pa RMS" in _gauge_sentence(gauge)
    assert not _gauge_left(36.0, channel, 1.12)["left"]
    # the floor known poorly from these replicates: the angle's allowance is the limit
    assert not _gauge_left(53.5, channel, 1.5)["left"]
    assert _gauge_left(None, channel, 1.1) is None
    assert _gauge_left(50.0, {"pressure_floor_pa": None}, 1.1) is None
    assert _gauge_sentence(None) is None
