"""The catalogue's contract: every effect is one object with parameters in units, a
plausible range inside its fit bounds, a null value that switches it off, a forward
transform at one stage, identifiability conditions and a sentence; and each transform
does what its docstring says (numbers from the transforms' own definitions)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from solver.design import Design
from solver.design_space import recognise
from surrogate.calibration.effects import CATALOGUE, EFFECTS, STAGES, DataTraits
from surrogate.calibration.effects.chamber_leak import leaked_volume_ul
from surrogate.calibration.effects.hydraulic_resistance import (
    R_CHANNEL,
    rectangular_channel_resistance_pa_per_ul_s,
)
from surrogate.calibration.effects.line_compliance import ATMOSPHERE_KPA, chamber_volume_ul
from surrogate.calibration.effects.viscoelastic_creep import prony_lag

TRAITS = DataTraits(has_time=True, has_flow=True, n_flow_rates=1, has_unloading=False,
                    has_holds=False, n_thicknesses_max=1, n_lengths_max=1,
                    open_parameters=())


@pytest.mark.parametrize("effect", CATALOGUE, ids=lambda e: e.id)
def test_every_effect_keeps_the_contract(effect):
    assert effect.stage in STAGES and effect.kind in ("physical", "measurement", "time")
    assert effect.parameters and effect.title and effect.description
    assert len(effect.measure_directly) > 20  # told when the data cannot tell it apart
    for p in effect.parameters:
        lo, hi = p.fit_bounds
        assert lo <= p.plausible[0] <= p.plausible[1] <= hi, p.name
        assert lo <= p.start <= hi
        assert p.unit
        if p.tested:
            assert lo <= p.null <= hi
    params = {p.name: {"value": p.start if not p.tested else p.plausible[1], "sd": 0.1,
                       "unit": p.unit} for p in effect.parameters}
    sentence = effect.interpret(params, {"flow_rates_ul_s": [2.5]})
    assert isinstance(sentence, str) and len(sentence) > 40
    d = effect.as_dict()
    assert d["id"] == effect.id and len(d["parameters"]) == len(effect.parameters)


@pytest.mark.parametrize("effect", [e for e in CATALOGUE if e.stage != "design"],
                         ids=lambda e: e.id)
def test_the_null_value_switches_a_transform_off(effect):
    values = {p.name: (p.null if p.tested else p.start) for p in effect.parameters}
    p = np.array([0.0, 500.0, 1500.0])
    a = np.array([[0.0, 5.0, 30.0, 30.0]])
    t = np.array([[0.0, 1.0, 2.0, 3.0]])
    if effect.stage == "pressure":
        out = effect.chamber_pressure(p, np.full(3, 2.5), np.ones(3), values)
        np.testing.assert_allclose(out, p)
    elif effect.stage == "volume":
        v_grid = np.linspace(0.0, 20.0, 5)
        pump = np.array([0.0, 7.5, 19.0])
        out = effect.chamber_volume(pump, v_grid, 100.0 * v_grid[None], np.zeros(3, int),
                                    values)
        np.testing.assert_allclose(out, pump)
    elif effect.stage == "angle":
        np.testing.assert_allclose(effect.observed(a, values), a)
    elif effect.lags == "volume":
        out = effect.delivered_volume(a, t, np.ones_like(a, bool), lambda v: 100.0 * v,
                                      values)
        np.testing.assert_allclose(out, a)
    else:
        np.testing.assert_allclose(effect.lag(a, t, np.ones_like(a, bool), values), a)


@pytest.mark.parametrize("effect", [e for e in CATALOGUE if e.stage == "pressure"],
                         ids=lambda e: e.id)
def test_a_pressure_effects_gauge_reading_inverts_its_chamber_pressure(effect):
    # the pressure-by-volume channel predicts the gauge from the chamber pressure: the
    # forward transform must undo the fit's own, at every flow direction, and move off null
    values = {p.name: p.plausible[1] for p in effect.parameters}
    p = np.array([0.0, 400.0, 1500.0])
    q, d = np.full(3, 2.5), np.array([1.0, 0.0, -1.0])
    gauge = effect.gauge_pressure(p, q, d, values)
    np.testing.assert_allclose(effect.chamber_pressure(gauge, q, d, values), p, atol=1e-9)
    assert not np.allclose(gauge[[0, 2]], p[[0, 2]])


def test_physical_effects_change_the_design_the_baseline_is_asked_for():
    d = Design(L_mm=7.1, t_mm=0.75)
    m = EFFECTS["membrane_stiffness"].design(d, 1.3)
    assert recognise(m.membrane_material) == ("ecoflex_00_30", pytest.approx(1.3))
    assert m.body_material == d.body_material
    b = EFFECTS["body_stiffness"].design(EFFECTS["body_stiffness"].design(d, 1.5), 0.8)
    assert recognise(b.body_material) == ("pdms_1_10", pytest.approx(1.2))
    assert EFFECTS["membrane_thickness"].design(d, -0.05).t_mm == pytest.approx(0.7)
    assert EFFECTS["chamber_length"].design(d, 0.5).L_mm == pytest.approx(7.6)


def test_hydraulic_drop_follows_the_flow_direction():
    e = EFFECTS["hydraulic_resistance"]
    out = e.chamber_pressure(np.full(3, 1000.0), np.full(3, 2.5), np.array([1.0, 0.0, -1.0]),
                             {"R_pa_per_ul_s": 40.0})
    np.testing.assert_allclose(out, [900.0, 1000.0, 1100.0])
    # Hagen-Poiseuille for the paper's channel, by hand: 12 mu L / (w h^3 (1 - 0.63 h/w)),
    # the shortcut for the exact series (within 1e-4 at h/w = 0.3; tests/test_hydraulics.py)
    r = 12e-3 * 3e-3 / (0.5e-3 * 0.15e-3**3 * (1 - 0.63 * 0.3)) * 1e-9
    assert R_CHANNEL == pytest.approx(r, rel=1e-4)
    assert R_CHANNEL == rectangular_channel_resistance_pa_per_ul_s(3, 0.5, 0.15)


def test_hydraulic_resistance_is_identifiable_only_when_the_flow_changes():
    e = EFFECTS["hydraulic_resistance"]
    assert "pressure offset" in e.not_identifiable(TRAITS)[0]
    for change in ({"n_flow_rates": 2}, {"has_unloading": True}, {"has_holds": True}):
        assert e.not_identifiable(DataTraits(**{**TRAITS.__dict__, **change})) is None


def test_creep_needs_holds_unloading_or_two_flow_rates():
    e = EFFECTS["viscoelastic_creep"]
    reason, measure = e.not_identifiable(TRAITS)
    assert "one flow rate" in reason and "hold" in measure
    for change in ({"n_flow_rates": 2}, {"has_unloading": True}, {"has_holds": True}):
        assert e.not_identifiable(DataTraits(**{**TRAITS.__dict__, **change})) is None
    no_time = DataTraits(**{**TRAITS.__dict__, "has_time": False, "has_holds": True})
    assert "time" in e.not_identifiable(no_time)[0]


def test_line_compliance_inverts_the_pump_volume_by_hand():
    # chamber p = k V (Pa per ul): V_pump = V + C k V, so V = V_pump / (1 + C k) exactly
    # (the relation is linear between the grid's nodes too)
    k_pa_per_ul, c_ul_per_kpa = 80.0, 2.0
    v_grid = np.linspace(0.0, 40.0, 41)
    p_grid = np.vstack([k_pa_per_ul * v_grid, 2 * k_pa_per_ul * v_grid])
    pump = np.array([0.0, 3.3, 10.0, 25.0, 3.3, 10.0])
    design = np.array([0, 0, 0, 0, 1, 1])
    out = EFFECTS["line_compliance"].chamber_volume(pump, v_grid, p_grid, design,
                                                    {"C_ul_per_kpa": c_ul_per_kpa})
    c = c_ul_per_kpa * 1e-3
    np.testing.assert_allclose(out, pump / (1.0 + c * k_pa_per_ul * (1 + design)), rtol=1e-12)
    # an air bubble of V ul reads as V / P_atm: 101.3 ul of air is 1 ul per kPa
    sentence = EFFECTS["line_compliance"].interpret(
        {"C_ul_per_kpa": {"value": 1.0, "sd": 0.1, "unit": "ul per kPa"}}, {})
    assert f"{ATMOSPHERE_KPA:.0f} ul of air" in sentence


def test_line_compliance_gives_no_volume_past_the_baselines_range():
    v_grid = np.linspace(0.0, 10.0, 11)
    p = np.where(v_grid <= 6.0, 100.0 * v_grid, np.nan)[None]        # ends at 6 ul
    # a pressure maximum: p falls after 4 ul; the pump's volume is kept non-decreasing
    p_max = np.minimum(100.0 * v_grid, 800.0 - 100.0 * v_grid)[None]
    pump = np.array([5.0, 6.0 + 0.001 * 600.0 + 0.1, np.nan])
    out = chamber_volume_ul(pump, v_grid, p, np.zeros(3, int), 1e-3)
    assert np.isfinite(out[0]) and np.isnan(out[1]) and np.isnan(out[2])
    after = chamber_volume_ul(np.linspace(0.0, 10.0, 50), v_grid, p_max, np.zeros(50, int),
                              1e-3)
    assert np.all(np.diff(after) >= 0.0) and np.all(np.isfinite(after))


def test_line_compliance_needs_the_volume_channel():
    e = EFFECTS["line_compliance"]
    reason, measure = e.not_identifiable(TRAITS)
    assert "injected volume" in reason and "time_s" in measure
    assert e.not_identifiable(DataTraits(**{**TRAITS.__dict__, "by_volume": True})) is None


def test_gains_are_not_fitted_against_a_baseline_that_leaves_them_open():
    open_ = DataTraits(**{**TRAITS.__dict__, "open_parameters": ("amplitude",
                                                                "pressure_scale")})
    assert "amplitude" in EFFECTS["camera_gain"].not_identifiable(open_)[0]
    assert "pressure scale" in EFFECTS["pressure_gain"].not_identifiable(open_)[0]
    assert EFFECTS["camera_gain"].not_identifiable(TRAITS) is None


def test_prony_lag_matches_a_fine_euler_integration():
    # static angle rising linearly for 4 s, then held: the delayed part creeps on.
    t = np.linspace(0.0, 10.0, 11)
    static = np.minimum(t, 4.0) * 5.0
    g, tau = 0.3, 2.0
    out = prony_lag(static[None], t[None], np.ones((1, 11), bool), g, tau)[0]
    tf = np.linspace(0.0, 10.0, 100001)
    sf = np.minimum(tf, 4.0) * 5.0
    y = np.empty_like(tf)
    y[0] = sf[0]
    e = math.exp(-(tf[1] - tf[0]) / tau)
    for i in range(1, tf.size):
        y[i] = sf[i] + (y[i - 1] - sf[i]) * e
    ref = (1 - g) * sf + g * y
    np.testing.assert_allclose(out, ref[::10000], atol=2e-3)
    assert out[4] < static[4] and 19.5 < out[-1] < 20.0  # creeps on towards 20 deg


def test_prony_lag_keeps_each_curve_its_own_and_its_state_still_over_the_padding():
    # three curves on their own uneven time grids, two padded after their last reading
    # (the calibration pads curves of unequal length so): each curve's lag is the one it
    # has alone, to the last bit, and the delayed state does not move over the padding
    rng = np.random.default_rng(3)
    n = (9, 14, 5)
    t = np.zeros((3, 14))
    static = np.full((3, 14), 1000.0)       # the padding's static value: never followed
    valid = np.zeros((3, 14), bool)
    for c, m in enumerate(n):
        t[c] = np.cumsum(rng.uniform(0.2, 1.5, 14)) - 0.2
        static[c, :m] = np.cumsum(rng.normal(2.0, 3.0, m))
        valid[c, :m] = True
    for g in (0.3, -0.25):   # the bend's creep and the gauge's relaxation
        out = prony_lag(static, t, valid, g, 1.7)
        for c, m in enumerate(n):
            alone = prony_lag(static[c:c + 1, :m], t[c:c + 1, :m], valid[c:c + 1, :m], g,
                              1.7)[0]
            np.testing.assert_array_equal(out[c, :m], alone)
            held = (alone[-1] - (1.0 - g) * static[c, m - 1]) / g     # the delayed state
            np.testing.assert_allclose(out[c, m:], (1.0 - g) * 1000.0 + g * held, rtol=1e-12)


def test_pressure_relaxation_overshoots_while_pumping_and_relaxes_in_a_hold():
    # a standard linear solid, by hand: the relaxed pressure rises 300 Pa/s for 4 s and is
    # held; the gauge reads (1 + g) p - g y with y the relaxed pressure delayed by tau
    e = EFFECTS["pressure_relaxation"]
    assert e.lags == "gauge" and e.stage == "time"
    t = np.linspace(0.0, 12.0, 13)
    static = np.minimum(t, 4.0) * 300.0
    g, tau = 0.25, 1.5
    out = e.lag(static[None], t[None], np.ones((1, 13), bool),
                {"g_relaxing": g, "tau_relaxation_s": tau})[0]
    # the ramp's exact solution: y = p - 300 tau (1 - exp(-t / tau)) while loading
    lag_at_4 = 300.0 * tau * (1.0 - math.exp(-4.0 / tau))
    assert out[4] == pytest.approx(1200.0 + g * lag_at_4, rel=1e-9)
    assert out[-1] == pytest.approx(1200.0 + g * lag_at_4 * math.exp(-8.0 / tau), rel=1e-9)
    assert np.all(np.diff(out[4:]) < 0)          # relaxes during the hold, to the static


def test_a_leak_drains_a_held_chamber_exponentially_by_hand():
    # p = k V held at V0 from t = 0: dV/dt = -G k V, V = V0 exp(-G k t); Heun's method on
    # 0.25 s steps is within 3e-4 of it (G k = 0.1 /s: second order, (0.025)^2 / 6 a step)
    k_pa_per_ul, g_ul_s_per_pa = 100.0, 1e-3
    t = np.linspace(0.0, 10.0, 41)[None]
    pump = np.full_like(t, 20.0)
    out = leaked_volume_ul(pump, t, np.ones(t.shape, bool), lambda v: k_pa_per_ul * v,
                           g_ul_s_per_pa)[0]
    np.testing.assert_allclose(out, 20.0 * np.exp(-g_ul_s_per_pa * k_pa_per_ul * t[0]),
                               rtol=3e-4)
    # past the baseline's range (NaN pressure) nothing leaks; the padding changes nothing
    valid = np.ones(t.shape, bool)
    valid[0, 30:] = False
    past = leaked_volume_ul(pump, t, valid, lambda v: np.full_like(v, np.nan),
                            g_ul_s_per_pa)
    np.testing.assert_allclose(past, pump)
    e = EFFECTS["chamber_leak"]
    assert e.stage == "time" and e.lags == "volume"
    assert "injected volume" in e.not_identifiable(TRAITS)[0]
    by_volume = DataTraits(**{**TRAITS.__dict__, "by_volume": True})
    assert "one flow rate" in e.not_identifiable(by_volume)[0]
    assert e.not_identifiable(DataTraits(**{**by_volume.__dict__, "has_holds": True})) is None


def test_gauge_drift_grows_with_the_runs_time_and_needs_a_hold_or_the_unloading():
    e = EFFECTS["gauge_drift"]
    assert e.lags == "gauge" and e.stage == "time"
    t = np.array([[0.0, 2.0, 5.0, 10.0]])
    static = np.array([[0.0, 400.0, 900.0, 900.0]])
    out = e.lag(static, t, np.ones(t.shape, bool), {"drift_pa_per_s": 3.0})
    np.testing.assert_allclose(out, static + 3.0 * t)     # 30 Pa above after 10 s
    by_volume = DataTraits(**{**TRAITS.__dict__, "by_volume": True})
    assert "one flow rate" in e.not_identifiable(by_volume)[0]
    assert e.not_identifiable(DataTraits(**{**by_volume.__dict__, "has_holds": True})) is None
    assert "injected volume" in e.not_identifiable(TRAITS)[0]


def test_a_falling_gauge_in_a_run_that_unloads_names_the_softening_on_unloading():
    """Mullins softening (the unloading's pressure below the loading's at one volume,
    outside the catalogue) was read as a gauge drift of -8.4 Pa/s on the fresh set N20
    with nothing said of it (benchmarks/RESULTS.md, forty-fifth session): a falling
    gauge in a run that unloads now names it and how to tell the two apart."""
    e = EFFECTS["gauge_drift"]
    falling = {"drift_pa_per_s": {"value": -8.36, "sd": 2.6}}
    unloads = {"unloading": True, "holds": True, "has_time_s": True}   # the report's data
    said = e.interpret(falling, unloads)
    assert "Mullins" in said and "at rest after the run" in said
    assert "Mullins" not in e.interpret(falling, {**unloads, "unloading": False})
    assert "Mullins" not in e.interpret({"drift_pa_per_s": {"value": 5.0, "sd": 1.0}},
                                        unloads)


def test_pressure_relaxation_needs_the_volume_channel_and_a_change_of_the_pump():
    e = EFFECTS["pressure_relaxation"]
    assert "injected volume" in e.not_identifiable(TRAITS)[0]
    by_volume = DataTraits(**{**TRAITS.__dict__, "by_volume": True})
    assert "one flow rate" in e.not_identifiable(by_volume)[0]
    for change in ({"n_flow_rates": 2}, {"has_unloading": True}, {"has_holds": True}):
        assert e.not_identifiable(DataTraits(**{**by_volume.__dict__, **change})) is None
