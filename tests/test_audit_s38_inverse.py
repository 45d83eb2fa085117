"""Inverse design audited against the FE in the thirty-eighth session (POST /v1/inverse
over the shipped emulator): a target asked at a pressure past every design's FE range got
"not reachable ...: widen the bounds (longer chamber, thinner membrane, softer membrane)
or raise the pressure" -- the wrong way: those designs pass the FE's range (90 deg, or the
blocked-tip force's 2500 Pa) before the target pressure."""

from __future__ import annotations

import pytest

PAIR = ["pdms_1_15/ecoflex_00_30"]


@pytest.mark.parametrize("target, bounds, lower_pa", [
    # soft designs bend past the FE's 90 deg long before 10 kPa (up to 89 deg at 3 kPa)
    ({"angle_deg": 30, "pressure_pa": 10000}, {"L_bounds_mm": [16, 18],
                                                "t_bounds_mm": [0.5, 0.6]}, 3000),
    # the blocked-tip force is modelled to 2500 Pa (the database's force range)
    ({"kind": "force_at_pressure", "force_mn": 1.0, "pressure_pa": 2800},
     {"L_bounds_mm": [8, 10]}, 2240),
])
def test_a_target_past_every_designs_fe_range_says_lower_the_pressure(
        shipped_client, target, bounds, lower_pa):
    r = shipped_client.post("/v1/inverse", json={"target": target, "material_pairs": PAIR,
                                                 **bounds})
    assert r.status_code == 200, r.text
    body = r.json()
    assert not body["feasible"] and body["candidates"] == []
    text = body["explanation"]
    assert "raise the pressure" not in text and "widen the bounds" not in text, text
    assert "past its FE range" in text and "lower the pressure (pressure_pa)" in text, text
    assert f"at {lower_pa:g} Pa designs there reach up to" in text, text


@pytest.mark.parametrize("kind", ["angle_at_pressure", "pressure_budget"])
def test_an_angle_past_the_fe_angle_stop_is_named_not_widen_the_bounds(shipped_client, kind):
    """120 deg at 3 kPa: soft designs reach the FE curves' end, 90 deg (the default
    solve's angle stop), well before; past it no angle is known. It said "the largest
    reachable at 3000 Pa is 90 deg: widen the bounds ... or raise the pressure"."""
    r = shipped_client.post("/v1/inverse", json={
        "target": {"kind": kind, "angle_deg": 120, "pressure_pa": 3000},
        "material_pairs": PAIR, "L_bounds_mm": [16, 18], "t_bounds_mm": [0.5, 0.6]})
    assert r.status_code == 200, r.text
    body = r.json()
    assert not body["feasible"] and body["candidates"] == []
    text = body["explanation"]
    assert "raise the pressure" not in text and "widen the bounds" not in text, text
    assert "past the FE's range, which ends at 90 deg" in text, text
    assert "ask for at most 90 deg in size (angle_deg)" in text, text
