"""The emulator ends a design's FE range at the default FE's pressure stop (20 kPa,
SolverSettings.max_pressure_pa) itself, on every path a Python caller reaches: by pressure,
by volume, inverse, many designs at once (inverse design) and the balance model. Before, only
the service cut there (service/pump.py): ``Emulator.predict`` answered two layers 50x their
presets to 105843 Pa (the judge audit of the thirty-sixth session, left then)."""

from dataclasses import replace

import numpy as np
import pytest

from solver.design import Design
from solver.design_space import scaled_material
from solver.settings import SolverSettings
from surrogate.emulator import load_emulator

EMULATOR = "service/data/emulator.json"
STOP_PA = SolverSettings().max_pressure_pa


@pytest.fixture(scope="module")
def emulator():
    return load_emulator(EMULATOR)


def scaled(design: Design, s: float) -> Design:
    """``design`` with both layers' mu x ``s``: the same curve at s x the pressures."""
    return replace(design, body_material=scaled_material("pdms_1_10", s),
                   membrane_material=scaled_material("ecoflex_00_30", s))


STANDARD = Design(L_mm=7.1, t_mm=0.5)


def test_by_pressure_the_range_ends_at_the_stop(emulator):
    plain = emulator.predict(STANDARD, [100.0])
    end_pa = plain.validity["fe_limit_pa"]
    s = 2.0 * STOP_PA / end_pa          # its FE range would end at twice the stop
    r = emulator.predict(scaled(STANDARD, s), [0.5 * STOP_PA, 0.99 * STOP_PA, 1.2 * STOP_PA])
    assert np.isfinite(r.angle_deg[:2]).all() and np.isnan(r.angle_deg[2])
    assert r.validity["fe_limit_pa"] == pytest.approx(STOP_PA, rel=1e-9)
    assert "pressure stop" in r.validity["fe_stop_reason"]
    assert {"past_fe_range", "past_fe_pressure_stop"} <= set(r.validity["flags"])
    # the angle at the stop: the unscaled design's at stop / s (the invariance)
    at = emulator.predict(STANDARD, [STOP_PA / s])
    assert r.validity["fe_limit_angle_deg"] == pytest.approx(at.angle_deg[0], abs=1e-6)
    assert r.validity["fe_limit_angle_deg"] < plain.validity["fe_limit_angle_deg"]
    assert r.validity["in_domain"] is True


def test_a_design_whose_range_ends_before_the_stop_is_unchanged(emulator):
    plain = emulator.predict(STANDARD, [100.0, 1e9])
    assert plain.validity["fe_limit_pa"] < STOP_PA
    assert "past_fe_pressure_stop" not in plain.validity["flags"]
    assert "pressure stop" not in plain.validity["fe_stop_reason"]


def test_by_volume_and_inverse_no_number_past_the_stop(emulator):
    s = 2.0 * STOP_PA / emulator.predict(STANDARD, [100.0]).validity["fe_limit_pa"]
    design = scaled(STANDARD, s)
    v = emulator.predict_volume(design, np.linspace(0.5, 40.0, 40))
    p = np.asarray(v.pressure_pa, float)
    assert np.nanmax(p) <= STOP_PA * (1 + 1e-9)
    assert np.isnan(v.angle_deg[-1]) and "past_fe_pressure_stop" in v.validity["flags"]
    assert v.validity["fe_limit_pa"] == pytest.approx(STOP_PA, rel=1e-9)
    inv = emulator.inverse(design, [3.0, 89.0])    # the stop comes at 6.7 deg
    assert np.isfinite(inv.pressure_pa[0]) and inv.pressure_pa[0] <= STOP_PA
    assert np.isnan(inv.pressure_pa[1]) and np.isnan(inv.volume_ul[1])
    assert "past_fe_pressure_stop" in inv.validity["flags"]


def test_many_designs_at_once_stop_there_too(emulator):
    """Inverse design (evaluate_designs) reads its own curves: the same stop."""
    designs = [STANDARD, scaled(STANDARD, 50.0)]
    out = emulator.evaluate_designs(designs, pressure_pa=0.99 * STOP_PA, angle_deg=89.0)
    one = emulator.predict(designs[1], [0.99 * STOP_PA])
    assert np.isnan(out["needed"][1])                   # 89 deg needs more than 20 kPa
    assert out["angle"][1] == pytest.approx(one.angle_deg[0], abs=1e-6)
    assert np.isnan(out["angle"][0])                     # the standard design: past 90 deg
    far = emulator.evaluate_designs(designs, pressure_pa=1.5 * STOP_PA, angle_deg=None)
    assert np.isnan(far["angle"]).all()


def test_the_balance_model_stops_there_too(emulator):
    """Ecoflex on Ecoflex near the stiffness balance, both layers x40 (the membrane then
    at 80x its preset, inside the 100x a layer may be): its FE range would end past the
    stop."""
    base = Design(L_mm=18, t_mm=0.5, T_mm=2, b_mm=2.4, h_mm=0.229415,
                  body_material=scaled_material("ecoflex_00_30", 0.5),
                  membrane_material=scaled_material("ecoflex_00_30", 2.0))
    plain = emulator.predict_volume(base, [100.0])
    if "near_stiffness_balance" not in plain.validity["flags"]:
        pytest.skip("this design is not answered by the balance model")
    s = 40.0
    assert plain.validity["fe_limit_pa"] * s > 1.5 * STOP_PA
    design = replace(base, body_material=scaled_material("ecoflex_00_30", 0.5 * s),
                     membrane_material=scaled_material("ecoflex_00_30", 2.0 * s))
    r = emulator.predict_volume(design, np.linspace(5.0, 480.0, 40))
    assert np.nanmax(np.asarray(r.pressure_pa, float)) <= STOP_PA * (1 + 1e-9)
    assert "past_fe_pressure_stop" in r.validity["flags"]
    assert "pressure stop" in r.validity["fe_stop_reason"]
    by_p = emulator.predict(design, [0.5 * STOP_PA, 1.5 * STOP_PA])
    assert np.isnan(by_p.angle_deg[1])
    # the inverse (the balance model's too): an angle the design reaches only past the stop
    target = 0.999 * plain.validity["fe_limit_angle_deg"]
    assert abs(r.validity["fe_limit_angle_deg"]) < abs(target)
    inv = emulator.inverse(design, [target])
    assert np.isnan(inv.pressure_pa[0]) and np.isnan(inv.volume_ul[0])
    assert {"past_fe_range", "past_fe_pressure_stop"} <= set(inv.validity["flags"])
