"""A volume-controlled curve lands on its stop instead of one ~8-degree step past it
(solver/landing.py): ``balloon solve --max-angle-deg 0.5`` had stored a curve to 0.93 deg,
a blocked tip asked to 2500 Pa had ended above it. Only the last point moves: the steps
before it are those of a solve without the landing.

FE cases on hex1 elements and a short chamber (~1400 dofs, 0.5-1.5 s each); the figures
of the former stepping are in the comments (measured 2026-12-06)."""

import numpy as np
import pytest

from solver import Design, SolverSettings, stop_landing
from solver.landing import (
    USER_STOP_CORRECTIONS,
    Point,
    land,
    landing_tolerance,
    stop_reason,
    volume_load_at,
)
from solver.materials import MATERIALS
from solver.stepping import solve

SHORT = Design(L_mm=4.1)
REVERSED = Design(L_mm=4.1, body_material=MATERIALS["ecoflex_00_30"],
                  membrane_material=MATERIALS["pdms_1_15"])
HALF_DEGREE = SolverSettings(element="hex1", max_angle_deg=0.5)


def without_landing(monkeypatch, design: Design, settings: SolverSettings):
    """The curve the stepping makes when no landing converges: the former one."""
    with monkeypatch.context() as m:
        m.setattr(stop_landing, "land", lambda *args, **kwargs: None)
        return solve(design, settings)


def assert_only_the_last_point_moved(landed, former) -> None:
    assert len(landed) == len(former)
    for name in landed.ARRAY_FIELDS:
        assert np.array_equal(getattr(landed, name)[:-1], getattr(former, name)[:-1],
                              equal_nan=True), name
    assert np.array_equal(landed.volume_control_negative_eigenvalues[:-1],
                          former.volume_control_negative_eigenvalues[:-1])
    # The landed step lies between the last two of the former curve, every column of it
    # from the one landed state.
    assert former.volume_ul[-2] < landed.volume_ul[-1] < former.volume_ul[-1]
    assert landed.time_s[-1] == landed.volume_ul[-1] / SolverSettings().flow_ul_s
    assert landed.status == former.status == "complete"
    # the former ended off its (user's) stop and says so, with where it ended
    assert former.reason == (f"{landed.reason}, ended at {former.angle_deg[-1]:.6g} deg: "
                             "past it by more than the landing's 0.0005 deg")


def test_a_half_degree_curve_ends_at_half_a_degree(monkeypatch):
    infos: list[dict] = []
    curve = solve(SHORT, HALF_DEGREE, on_step=infos.append)
    # Formerly 0.711 deg (the standard design's: 0.93 deg).
    assert 0.5 <= curve.angle_deg[-1] <= 0.5 + landing_tolerance("max_angle_deg", 0.5)
    assert curve.reason == "reached max_angle_deg = 0.5"
    # The job's last progress report is the landed point.
    assert infos[-1]["step"] == len(curve) - 1
    assert infos[-1]["angle_deg"] == curve.angle_deg[-1]
    assert infos[-1]["volume_ul"] == curve.volume_ul[-1]
    former = without_landing(monkeypatch, SHORT, HALF_DEGREE)
    assert former.angle_deg[-1] > 0.7
    assert_only_the_last_point_moved(curve, former)
    assert curve.timings_s["landing_steps"] >= 1


def test_a_reversed_pair_ends_at_minus_the_stop():
    curve = solve(REVERSED, HALF_DEGREE)
    # Formerly -0.721 deg; the stop is on the angle's magnitude.
    assert -0.5 - landing_tolerance("max_angle_deg", 0.5) <= curve.angle_deg[-1] <= -0.5
    assert np.all(curve.angle_deg[1:] < 0)


def test_the_volume_stop_is_landed_by_capping_the_last_step(monkeypatch):
    settings = SolverSettings(element="hex1", max_volume_ul=3.0)
    curve = solve(SHORT, settings)
    # Formerly 3.463 ul; no landing search, the last step's volume capped at the stop.
    assert curve.reason == "reached max_volume_ul = 3.0"
    assert 3.0 <= curve.volume_ul[-1] <= 3.0 + 1e-6
    assert "landing_steps" not in curve.timings_s
    assert curve.volume_ul[-2] < 3.0


def test_a_blocked_tip_lands_on_its_pressure_stop():
    curve = solve(SHORT, SolverSettings(element="hex1", tip="blocked", max_pressure_pa=2500))
    # Formerly 2582 Pa.
    assert curve.reason == "reached max_pressure_pa = 2500"
    assert 2500 <= curve.pressure_pa[-1] <= 2500 + landing_tolerance("max_pressure_pa", 2500)
    assert np.all(np.abs(curve.tip_displacement_mm[:, 1]) < 1e-12)
    assert curve.force_mn[-1] > curve.force_mn[-2] > 0


def test_a_landing_that_does_not_converge_keeps_the_step_past_the_stop(monkeypatch):
    original_land = stop_landing.land

    def failing_steps(*args, **kwargs):
        raise stop_landing.StepFailed("made to fail")

    def land_failing(*args, **kwargs):
        # Every Newton step of the landing fails, from the predictor and from the state.
        with monkeypatch.context() as m:
            m.setattr(stop_landing, "mixed_newton_step", failing_steps)
            return original_land(*args, **kwargs)

    former = without_landing(monkeypatch, SHORT, HALF_DEGREE)
    monkeypatch.setattr(stop_landing, "land", land_failing)
    infos: list[dict] = []
    curve = solve(SHORT, HALF_DEGREE, on_step=infos.append)
    assert curve.status == "complete"
    assert curve.reason.startswith("reached max_angle_deg = 0.5, ended at 0.7")
    for name in curve.ARRAY_FIELDS:
        assert np.array_equal(getattr(curve, name), getattr(former, name), equal_nan=True), name
    assert curve.timings_s["landing_steps"] == 1
    assert infos[-1]["angle_deg"] == former.angle_deg[-1]


def test_a_landing_whose_corrections_fail_keeps_the_nearest_state_past_the_stop():
    # The stop 0.5 with the window [0.5, 0.501]: a landing at 0.54 is kept when its
    # correction does not converge; one short of the stop, at 0.46, never is.
    def first_only(value: float, tried: list[float]):
        def converge(load):
            tried.append(load)
            return Point(load, value) if len(tried) == 1 else None
        return converge

    for first, kept in ((0.54, 0.54), (0.46, None)):
        tried: list[float] = []
        best = land(0.5, 0.001, Point(0.0, 0.0), Point(1.0, 1.0), first_only(first, tried))
        assert tried[0] == pytest.approx(0.5005) and len(tried) == 2
        assert (best and best.value) == kept
    # A step already in the window needs no landing.
    tried = []
    assert land(0.5, 0.001, Point(0.0, 0.0), Point(1.0, 0.5004),
                first_only(0.5, tried)) is None and tried == []


def test_the_corrections_stay_inside_the_bracket_past_a_pressure_maximum():
    # The pressure rises to a maximum of 2600 Pa at load 1 and falls to 2575 Pa at 1.25,
    # within the step: the stop 2500 Pa is met on the rising part (load 0.5), and every
    # load tried lies between a state below the stop and one past it (a secant through
    # the last two states, both past the maximum, would have gone to load 2).
    def pressure_pa(load):
        return 2600.0 - 400.0 * (load - 1.0) ** 2

    tried: list[float] = []

    def converge(load):
        tried.append(load)
        return Point(load, pressure_pa(load))

    best = land(2500.0, 2.5, Point(0.0, 2200.0), Point(1.25, 2575.0), converge)
    assert len(tried) == 3 and all(0.0 < load < 1.25 for load in tried)
    assert best.value == min(pressure_pa(load) for load in tried) < 2575.0


def test_the_cavity_volume_at_the_volume_stop():
    # The half model injects twice its cavity's change.
    assert volume_load_at(3.0, lambda v: 2.0 * (v - 1.5), 1.5) == pytest.approx(3.0)


def test_pressure_control_is_unchanged():
    # Its last step's pressure was already capped at max_pressure_pa; its angle stop is
    # still met one step past (no landing under pressure control), which the reason of
    # this user's stop says (the forty-second session).
    by_pressure = SolverSettings(element="hex1", control="pressure", max_angle_deg=0.5)
    curve = solve(SHORT, by_pressure)
    assert curve.angle_deg[-1] > 0.55
    assert curve.reason == (f"reached max_angle_deg = 0.5, ended at {curve.angle_deg[-1]:.6g}"
                            " deg: past it by more than the landing's 0.0005 deg")
    assert "landing_steps" not in curve.timings_s
    capped = solve(SHORT, SolverSettings(element="hex1", control="pressure",
                                         max_pressure_pa=300.0))
    assert capped.reason == "reached max_pressure_pa = 300.0"
    assert capped.pressure_pa[-1] == 300.0


# -- the forty-second session: a user's stop on a convex curve ---------------------------

def cubic_angle(load: float) -> float:
    """The angle's rise near rest, about the cube of the volume: a convex curve."""
    return load ** 3


def test_a_users_stop_lands_on_a_convex_curve_by_the_illinois_corrections():
    """The interpolation and its two secant corrections (a regula falsi) all land short
    on a convex curve, the end past the stop never moves, and no state is kept: the curve
    ended at the step past the stop. The Illinois corrections a user's stop gets land in
    the window [0.1, 0.1001]; the defaults' landing (``further=0``) is left as it was."""
    def converge(load):
        tried.append(load)
        return Point(load, cubic_angle(load))

    window = landing_tolerance("max_angle_deg", 0.1)
    below, above = Point(0.0, 0.0), Point(0.58, cubic_angle(0.58))     # 0.195 deg
    tried: list[float] = []
    assert land(0.1, window, below, above, converge) is None          # the former landing
    assert len(tried) == 3 and all(cubic_angle(x) < 0.1 for x in tried)
    tried = []
    best = land(0.1, window, below, above, converge, further=USER_STOP_CORRECTIONS)
    assert 0.1 <= best.value <= 0.1 + window
    assert all(0.0 < x < 0.58 for x in tried) and len(tried) <= 3 + USER_STOP_CORRECTIONS


def test_a_tenth_of_a_degree_is_landed_on():
    """``balloon solve --max-angle-deg 0.1`` ended at 0.19 deg (here 0.183, hex1) and said
    "reached max_angle_deg = 0.1"."""
    curve = solve(SHORT, SolverSettings(element="hex1", max_angle_deg=0.1))
    assert 0.1 <= curve.angle_deg[-1] <= 0.1 + landing_tolerance("max_angle_deg", 0.1)
    assert curve.reason == "reached max_angle_deg = 0.1"


def test_a_default_stop_keeps_its_words_off_the_window():
    """The defaults' stops (90 deg, 20 kPa: the database's curves) keep their reason as it
    was; a user's says where the curve ended when it is off the stop."""
    assert stop_reason("max_angle_deg", 90.0, 90.4, user_stop=False) == \
        "reached max_angle_deg = 90.0"
    assert stop_reason("max_angle_deg", 0.1, 0.10005, user_stop=True) == \
        "reached max_angle_deg = 0.1"
    assert stop_reason("max_pressure_pa", 2500.0, 2600.0, user_stop=True) == (
        "reached max_pressure_pa = 2500.0, ended at 2600 Pa: past it by more than the "
        "landing's 2.5 Pa")
