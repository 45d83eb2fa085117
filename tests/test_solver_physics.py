"""Physical trends on a coarse mesh (fast): the paper's qualitative findings.

Source of each expectation: the paper (Kumar et al., Sections 3.2-3.4): the angle grows
with chamber length, falls with membrane thickness, and swapping the layers' materials
(Ecoflex body, PDMS 1:15 membrane) reverses the bending direction."""

import numpy as np
import pytest

from solver import Design, SolverSettings, get_material, solve

COARSE = SolverSettings(mesh_level=0, element="hex1", max_angle_deg=8, max_pressure_pa=4000)


def _angle_at(curve, pressure_pa):
    return float(np.interp(pressure_pa, curve.pressure_pa, curve.angle_deg))


@pytest.fixture(scope="module")
def standard():
    return solve(Design(), COARSE)


def test_standard_curve_is_complete_and_bends_away_from_membrane(standard):
    assert standard.status == "complete"
    assert standard.angle_deg[-1] >= 8
    assert np.all(np.diff(standard.volume_ul) > 0)
    assert standard.pressure_pa[-1] > 0
    assert np.allclose(standard.time_s, standard.volume_ul / 2.5)
    assert np.all(standard.max_membrane_stretch >= 1.0)


def test_angle_grows_with_chamber_length(standard):
    longer = solve(Design(L_mm=11.1), COARSE)
    p = 0.9 * min(standard.pressure_pa[-1], longer.pressure_pa[-1])
    assert _angle_at(longer, p) > 1.3 * _angle_at(standard, p)


def test_angle_falls_with_membrane_thickness(standard):
    thicker = solve(Design(t_mm=1.0), COARSE)
    p = 0.9 * min(standard.pressure_pa[-1], thicker.pressure_pa[-1])
    assert _angle_at(thicker, p) < 0.7 * _angle_at(standard, p)


def test_reversed_materials_bend_the_other_way():
    reversed_pair = Design(body_material=get_material("ecoflex_00_30"),
                           membrane_material=get_material("pdms_1_15"))
    curve = solve(reversed_pair, SolverSettings(mesh_level=0, element="hex1",
                                                max_angle_deg=5, max_pressure_pa=4000))
    assert curve.status == "complete"
    assert curve.angle_deg[-1] < -4


def test_pressure_and_volume_control_agree(standard):
    pc = solve(Design(), SolverSettings(mesh_level=0, element="hex1", control="pressure",
                                        max_pressure_pa=1000))
    assert pc.status == "complete"
    assert pc.angle_deg[-1] < standard.angle_deg[-1]   # inside the volume-control curve
    expected = _angle_at(standard, pc.pressure_pa[-1])
    assert pc.angle_deg[-1] == pytest.approx(expected, rel=0.02)


def test_blocked_tip_gives_a_positive_force():
    curve = solve(Design(), SolverSettings(mesh_level=0, element="hex1", tip="blocked",
                                           max_pressure_pa=1200))
    assert np.all(np.abs(curve.tip_displacement_mm[:, 1]) < 1e-12)
    # Above the transition regime the force grows with pressure.
    above = curve.pressure_pa > 500
    assert curve.force_mn[-1] > 0
    assert np.all(np.diff(curve.force_mn[above]) > 0)
