"""The inlet's hydraulic resistance (surrogate/hydraulics.py) against hand computations."""

from __future__ import annotations

import math

import pytest

from solver.errors import InputError
from surrogate.hydraulics import (
    Inlet,
    rectangular_channel_resistance_pa_per_ul_s,
    round_tube_resistance_pa_per_ul_s,
)


def test_the_papers_channel_by_hand():
    # w = 0.5 mm, h = 0.15 mm, L = 3 mm, mu = 1e-3 Pa s. 12 mu L / (w h^3) =
    # 12 * 1e-3 * 3e-3 / (0.5e-3 * 3.375e-12) = 2.1333e13 Pa s/m^3. The bracket:
    # 192 h / (pi^5 w) = 192 * 0.3 / 306.0197 = 0.188223; sum tanh(n pi w/2h)/n^5 over odd n:
    # tanh(5.23599) = 0.999943, + 1/243 + 1/3125 + 1/16807 + 1/59049 + 1/161051 + ... = 1.004455;
    # bracket = 1 - 0.188223 * 1.004455 = 0.810939; R = 2.1333e13 / 0.810939 = 2.6307e13
    # Pa s/m^3 = 26.307 Pa per ul/s.
    r = rectangular_channel_resistance_pa_per_ul_s(3.0, 0.5, 0.15)
    assert r == pytest.approx(26.307, rel=2e-5)
    assert Inlet().resistance_pa_per_ul_s == r
    # the shortcut 1 - 0.63 h/w: 2.1333e13 / 0.811 = 26.305 Pa per ul/s
    assert r == pytest.approx(26.305, rel=1e-4)
    # h and w swapped: the same duct
    assert rectangular_channel_resistance_pa_per_ul_s(3.0, 0.15, 0.5) == r


def test_a_square_duct_and_a_wide_slot():
    # square duct (h = w = 1 mm, L = 1 mm): the known constant R = 28.454 mu L / w^4
    # = 28.454 * 1e-3 * 1e-3 / 1e-12 = 2.8454e7 Pa s/m^3 = 2.8454e-2 Pa per ul/s
    assert rectangular_channel_resistance_pa_per_ul_s(1.0, 1.0, 1.0) == pytest.approx(
        2.8454e-2, rel=2e-4)
    # a slot 100 times wider than high tends to parallel plates, 12 mu L / (w h^3 (1 - 0.63 h/w))
    slot = rectangular_channel_resistance_pa_per_ul_s(1.0, 10.0, 0.1)
    assert slot == pytest.approx(12e-3 * 1e-3 / (10e-3 * 1e-12 * (1 - 0.0063)) * 1e-9, rel=1e-5)


def test_tubing_adds_in_series_and_the_pump_reads_r_q_above_the_chamber():
    # 1 m of 0.5 mm bore: 8 mu L / (pi r^4) = 8e-3 / (pi * (0.25e-3)^4) = 8e-3 / 1.22718e-14
    # = 6.5190e11 Pa s/m^3 = 651.90 Pa per ul/s
    assert round_tube_resistance_pa_per_ul_s(1000.0, 0.5) == pytest.approx(651.90, rel=1e-4)
    inlet = Inlet(tubing_length_mm=1000.0, tubing_bore_mm=0.5)
    assert inlet.resistance_pa_per_ul_s == pytest.approx(26.307 + 651.90, rel=1e-4)
    # at the paper's 2.5 ul/s: (26.307 + 651.90) * 2.5 = 1695.5 Pa above the chamber
    assert inlet.pressure_drop_pa(2.5) == pytest.approx(1695.5, rel=1e-4)
    # viscosity scales R linearly (glycerol-water, 10 mPa s: ten times)
    thick = Inlet(viscosity_pa_s=1e-2)
    assert thick.resistance_pa_per_ul_s == pytest.approx(263.07, rel=2e-5)


def test_laminar_flow_is_checked_and_bad_dimensions_are_named():
    # channel at 2.5 ul/s: U = 2.5e-9 / 7.5e-8 = 0.0333 m/s, D_h = 2 w h / (w + h) =
    # 0.23077 mm, Re = 998 * 0.0333 * 2.3077e-4 / 1e-3 = 7.68
    assert Inlet().reynolds_number(2.5) == pytest.approx(7.677, rel=1e-3)
    with pytest.raises(InputError) as err:
        Inlet(channel_height_mm=0.01, channel_width_mm=0.01).pressure_drop_pa(1000.0)
    assert err.value.field == "flow_ul_s" and "laminar" in str(err.value)
    with pytest.raises(InputError) as err:
        Inlet(tubing_length_mm=500.0)
    assert err.value.field == "inlet.tubing_bore_mm"
    with pytest.raises(InputError) as err:
        Inlet(channel_width_mm=-1.0)
    assert err.value.field == "inlet.channel_width_mm"
    assert math.isfinite(Inlet(tubing_length_mm=0.0).resistance_pa_per_ul_s)


def test_the_lines_time_constant_by_hand():
    """tau = R V_line / K: the fluid's compressibility behind the resistance. The paper's
    channel: R 26.3 Pa per ul/s, 0.225 ul of water, tau = 26.3 x 0.225 / 2.2e9 s."""
    from surrogate.hydraulics import WATER_BULK_MODULUS_PA

    paper = Inlet()
    assert paper.line_volume_ul == pytest.approx(0.5 * 0.15 * 3.0)
    assert paper.time_constant_s == pytest.approx(
        paper.resistance_pa_per_ul_s * 0.225 / WATER_BULK_MODULUS_PA, rel=1e-12)
    assert paper.time_constant_s < 1e-8
    viscous = Inlet(tubing_length_mm=1e5, tubing_bore_mm=0.05, viscosity_pa_s=100.0)
    tube_ul = math.pi * 0.05**2 / 4 * 1e5
    assert viscous.line_volume_ul == pytest.approx(0.225 + tube_ul)
    r_tube = 8 * 100.0 * 100.0 / (math.pi * 0.025e-3**4) * 1e-9      # Pa per ul/s
    assert viscous.time_constant_s == pytest.approx(
        (r_tube + Inlet(viscosity_pa_s=100.0).resistance_pa_per_ul_s) * viscous.line_volume_ul
        / WATER_BULK_MODULUS_PA, rel=1e-9)
    assert 5e6 < viscous.time_constant_s < 7e6


def test_no_pump_gauge_reading_before_the_line_carries_the_flow(shipped_client):
    """100 Pa s in 100 m of 0.05 mm tubing read 1.6e14 Pa at the pump gauge with a 200
    (two audits of the thirty-seventh session): the steady R Q is never reached there."""
    viscous = {"tubing_length_mm": 1e5, "tubing_bore_mm": 0.05, "viscosity_pa_s": 100.0}
    body = shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5}, "volumes_ul": [1.0, 5.0], "flow_ul_s": 2.5,
        "inlet": viscous}).json()
    assert body["pump_pressure_pa"] == [None, None]
    assert body["pressure_pa"][0] is not None and body["angle_deg"][0] is not None
    assert "pump_pressure_not_steady" in body["validity"]["flags"]
    assert body["validity"]["in_domain"] is True
    assert body["inlet"]["time_constant_s"] > 1e6
    inverse = shipped_client.post("/v1/inverse/pressure", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5}, "angles_deg": [10.0], "flow_ul_s": 2.5,
        "inlet": viscous}).json()
    assert inverse["pump_pressure_pa"] == [None]
    assert "pump_pressure_not_steady" in inverse["validity"]["flags"]
    r = shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5}, "pressures_pa": [2000.0], "flow_ul_s": 2.5,
        "inlet": viscous, "pressures_at": "pump_gauge"})
    assert r.status_code == 422
    assert r.json()["errors"][0]["field"] == "pressures_at"
    # the paper's channel: the gauge at every point, as before, and tau said
    plain = shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5}, "volumes_ul": [1.0, 5.0], "flow_ul_s": 2.5,
        "inlet": {}}).json()
    assert None not in plain["pump_pressure_pa"]
    assert "pump_pressure_not_steady" not in plain["validity"]["flags"]
    assert plain["inlet"]["time_constant_s"] < 1e-8
