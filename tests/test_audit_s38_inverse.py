"""Inverse design audited against the FE in the thirty-eighth session (POST /v1/inverse
over the shipped emulator): a target asked at a pressure past every design's FE range got
"not reachable ...: widen the bounds (longer chamber, thinner membrane, softer membrane)
or raise the pressure" -- the wrong way: those designs pass the FE's range (90 deg, or the
blocked-tip force's 2500 Pa) before the target pressure."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

PAIR = ["pdms_1_15/ecoflex_00_30"]


@pytest.mark.parametrize("target, bounds, lower_pa, where", [
    # soft designs bend past the FE's 90 deg long before 10 kPa (up to 89 deg at 3 kPa)
    ({"angle_deg": 30, "pressure_pa": 10000}, {"L_bounds_mm": [16, 18],
                                                "t_bounds_mm": [0.5, 0.6]}, 3000,
     "(they reach 30 deg at "),
    # the blocked-tip force is modelled to 2500 Pa (the database's force range)
    ({"kind": "force_at_pressure", "force_mn": 1.0, "pressure_pa": 2800},
     {"L_bounds_mm": [8, 10]}, 2240, "mN: lower the pressure"),
])
def test_a_target_past_every_designs_fe_range_says_lower_the_pressure(
        shipped_client, target, bounds, lower_pa, where):
    r = shipped_client.post("/v1/inverse", json={"target": target, "material_pairs": PAIR,
                                                 **bounds})
    assert r.status_code == 200, r.text
    body = r.json()
    assert not body["feasible"] and body["candidates"] == []
    text = body["explanation"]
    assert "raise the pressure" not in text and "widen the bounds" not in text, text
    assert "past its FE range" in text and "lower the pressure (pressure_pa)" in text, text
    assert f"at {lower_pa:g} Pa designs there reach up to" in text and where in text, text


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


# designs the search listed, solved by the default FE (the file names its source)
FE_CASES = json.loads((Path(__file__).parent / "data" / "fe_inverse_search_s38.json")
                      .read_text())
# Left open (thirty-eighth session): the designs a force search lists near the top of what
# the box reaches are those whose blocked-tip FE curve fails soon past the target pressure
# (2150-2230 Pa for 1 mN at 2000 Pa): there the force / free-angle ratio is learned from the
# blocked curves that run on, and read 14 % high (the free angle is right: 54.9 deg emulated,
# 55.2 FE, rank 1); and the best force "reachable" at 2000 Pa, 1.53 mN, was at a design whose
# blocked-tip FE failed at 1909 Pa. Since the thirty-ninth session the emulator knows where
# each design's blocked-tip curve ends (surrogate/emulator/blocked_range.py) and gives no
# force in its last 10 %: ranks 1 and 2 and the "best reachable" get none at 2000 Pa (their
# FE curves end at 2175, 2150 and 1909 Pa); and each force node is conditioned on every
# design that reaches it (surrogate/emulator/force_gps.py): rank 3 is answered 0.88 mN, its
# band covering the FE's 0.848 (1.000 before), and no design reaches 1 mN at 2000 Pa
# (0.93 mN the most). Left: the two Q4c designs, a few % outside narrow bands, and since
# the force bands' calibration on random blocked-tip designs (forty-fourth session: every
# half-width x 0.72-0.76, the held-out force3040 points covered 0.993 -> 0.966) a third,
# 0.6 % outside: one of the 5 % a 95 % band leaves out.
FORCE_OPEN = {
    "Q4c-rank1": "FE 0.318 mN above the band 0.287-0.314 (answer 0.300)",
    "Q4c-rank2": "FE 0.315 mN above the band 0.287-0.314 (answer 0.300)",
    "Q4c-rank3": "FE 0.302 mN above the band 0.287-0.300 (answer 0.294)",
}
NEAR_END = 1.15    # an FE curve failing within this x the asked pressure: near its end


@pytest.mark.parametrize("case", [
    pytest.param(c, id=c["id"], marks=([pytest.mark.xfail(reason=FORCE_OPEN[c["id"]],
                                                          strict=False)]
                                       if c["id"] in FORCE_OPEN else []))
    for c in FE_CASES["force_cases"]])
def test_force_search_answers_against_the_blocked_tip_fe(shipped_client, case):
    """The designs POST /v1/inverse listed for a blocked-tip force (1 mN at 2000 Pa over
    the box; 0.3 mN at 2000 Pa, L pinned to 10 mm), solved by the default FE with the tip
    held (tests/data/fe_inverse_search_s38.json, its source named there): the force's band
    at the target pressure covers the FE's; no force is given where the FE has none, and
    none is withheld but near the end of the design's blocked-tip FE curve."""
    r = shipped_client.post("/v1/predict", json={"design": case["design"],
                                                 "pressures_pa": [case["pressure_pa"]]})
    assert r.status_code == 200, r.text
    body = r.json()
    force = (body.get("force_mn") or [None])[0]
    if case["fe_force_mn"] is None:
        assert force is None or np.isnan(force), (force, case["fe_reason"])
        return
    if force is None or np.isnan(force):
        # withheld only near the end of the design's blocked-tip FE curve, and said so
        assert case["fe_status"] == "failed", case["fe_reason"]
        assert case["fe_last_pressure_pa"] < NEAR_END * case["pressure_pa"], case["fe_reason"]
        assert "force_past_fe_range" in body["validity"]["flags"]
        return
    lo, hi = body["force_lower_mn"][0], body["force_upper_mn"][0]
    assert lo <= case["fe_force_mn"] <= hi, (case["fe_force_mn"], lo, hi)


@pytest.mark.parametrize("case", FE_CASES["angle_cases"], ids=lambda c: c["id"])
def test_angle_search_answers_against_the_fe(shipped_client, case):
    """The designs POST /v1/inverse listed for angle targets -- 60 deg at 3 kPa over the
    box and in a narrow box of one pair, 45 deg within 1500 Pa (compact), 30 deg at 1 kPa
    with both layers' stiffness scaled, -40 deg at 2 kPa (the reversed pair), 45 deg at
    2 kPa with L pinned, -30 deg at 1200 Pa (Ecoflex on Ecoflex), 70 deg within 2500 Pa
    by margin -- solved by the default FE: the answer's band at the target pressure (a
    budget's: at the pressure it needs) covers the FE's angle (all 16 did)."""
    r = shipped_client.post("/v1/predict", json={"design": case["design"],
                                                 "pressures_pa": [case["pressure_pa"]]})
    assert r.status_code == 200, r.text
    body = r.json()
    lo, hi = sorted((body["lower_deg"][0], body["upper_deg"][0]))
    assert lo <= case["fe_angle_deg"] <= hi, (case["fe_angle_deg"], lo, hi)


def test_an_angle_past_every_curves_end_is_named_where_no_design_comes_near(shipped_client):
    """120 deg at 1000 Pa with short chambers (L 4-6 mm): the designs reach 11.6 deg
    there, and the answer said "widen the bounds ... or raise the pressure" -- but every
    database curve ends at 90 deg (the default solve's angle stop): no bound or pressure
    gives a known angle of 120 deg."""
    r = shipped_client.post("/v1/inverse", json={
        "target": {"kind": "angle_at_pressure", "angle_deg": 120, "pressure_pa": 1000},
        "material_pairs": PAIR, "L_bounds_mm": [4, 6]})
    assert r.status_code == 200, r.text
    text = r.json()["explanation"]
    assert "raise the pressure" not in text and "widen the bounds" not in text, text
    assert "past the FE's range, which ends at 90 deg" in text, text
    assert "ask for at most 90 deg in size (angle_deg)" in text, text
    # below the stop the way on is still more pressure or wider bounds
    r = shipped_client.post("/v1/inverse", json={
        "target": {"kind": "angle_at_pressure", "angle_deg": 85, "pressure_pa": 1000},
        "material_pairs": PAIR, "L_bounds_mm": [4, 6]})
    assert "raise the pressure" in r.json()["explanation"]
