"""The design search in a syringe-pump user's terms (issue 17, forty-second session): a lab
sets a flow rate and a time, or an injected volume, not a pressure. Targets
angle_at_volume, volume_budget, angle_at_time and time_budget (surrogate/search/pump_targets.py);
before this session POST /v1/inverse and `balloon inverse` took angle_at_pressure,
pressure_budget and force_at_pressure only, and `--flow-ul-s` given to a search was
silently dropped. The top-ranked designs of three searches were solved by the default FE
under volume control (tests/data/fe_pump_search_s42.json names its source)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from service_fakes import assert_problem
from test_harden_s30_cli import _one_line_error

from service.cli import main
from service.settings import DATA_DIR
from solver.design import design_from_dict
from surrogate import DesignTarget
from surrogate.emulator import load_emulator
from surrogate.search.design_search import SearchBounds, search_designs

CASES = json.loads((Path(__file__).parent / "data" / "fe_pump_search_s42.json").read_text())
PAIR = ["pdms_1_10/ecoflex_00_30"]
# a small box of one pair: a search in a few seconds
BOUNDS = {"material_pairs": PAIR, "L_bounds_mm": [10, 14], "t_bounds_mm": [0.6, 1.0]}


@pytest.fixture(scope="module")
def emulator():
    return load_emulator(DATA_DIR / "emulator.json")


def _fe_at(case: dict) -> tuple[float, float]:
    """The FE angle (deg) at the target volume, linear in volume between its steps, and
    the FE volume (ul) at the target angle."""
    fe = case["fe_curve"]
    v, a = np.array(fe["volume_ul"]), np.array(fe["angle_deg"])
    t = case["target"]
    volume = t.get("volume_ul") or t["time_s"] * t["flow_ul_s"]
    sign = np.sign(t["angle_deg"])
    at_volume = float(np.interp(volume, v, a)) if volume <= v[-1] else float("nan")
    return at_volume, float(np.interp(abs(t["angle_deg"]), sign * a, v))


@pytest.mark.parametrize("case", CASES["cases"], ids=[c["id"] for c in CASES["cases"]])
def test_the_fe_under_volume_control_lies_in_the_listed_bands(emulator, case):
    """The listed design's answers by volume (what the search reports) hold against the
    default FE: the volume for the target angle inside its band, and where the design is
    within its FE range at the target volume, the angle there inside its band."""
    design = design_from_dict(case["design"])
    t = case["target"]
    volume = t.get("volume_ul") or t["time_s"] * t["flow_ul_s"]
    fe_angle, fe_volume = _fe_at(case)
    inv = emulator.inverse(design, [t["angle_deg"]])
    assert inv.volume_lower_ul[0] <= fe_volume <= inv.volume_upper_ul[0], (
        fe_volume, inv.volume_lower_ul[0], inv.volume_upper_ul[0])
    at = emulator.predict_volume(design, [volume])
    if np.isfinite(fe_angle):
        lo, hi = sorted((at.lower_deg[0], at.upper_deg[0]))
        assert lo <= fe_angle <= hi, (fe_angle, lo, hi)
    else:       # the FE curve ends before the volume (its 90-deg stop): no number there
        assert np.isnan(at.angle_deg[0]) and "past_fe_range" in at.validity["flags"]
    # the numbers the search listed (with the fit of the forty-second session) lie in
    # today's bands: a refit moves them within their bands, not past them (until the
    # forty-fourth session pinned to 1e-3, which the refit on the box's faces broke at
    # 7.135 -> 7.115 ul; that the search lists a design's answers by volume is
    # test_the_batch_screen_reads_as_one_design_at_a_time)
    listed = case["listed"]
    assert inv.volume_lower_ul[0] <= listed["volume_needed_ul"] <= inv.volume_upper_ul[0]
    if listed["angle_at_volume_deg"] is not None:
        lo, hi = sorted((at.lower_deg[0], at.upper_deg[0]))
        assert lo <= listed["angle_at_volume_deg"] <= hi


def test_a_volume_target_lists_the_volume_the_angle_and_the_pressure(shipped_client):
    """45 deg at 20 ul: each listed design needs 20 ul (to 1 %) for 45 deg, with a band;
    at 20 ul it reads 45 deg with a band and a chamber pressure; the curve is drawn by
    injected volume to 20 ul; there is no target pressure (value_at_pressure null)."""
    r = shipped_client.post("/v1/inverse", json={
        "target": {"kind": "angle_at_volume", "volume_ul": 20, "angle_deg": 45},
        "n_results": 2, **BOUNDS})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["feasible"] and body["objective"] == "certainty", body["explanation"]
    for c in body["candidates"]:
        assert c["volume_needed_ul"] == pytest.approx(20, rel=0.01)
        assert c["volume_lower_ul"] < c["volume_needed_ul"] < c["volume_upper_ul"]
        assert c["angle_at_volume_deg"] == pytest.approx(45, rel=0.01)
        assert (c["angle_at_volume_lower_deg"] < c["angle_at_volume_deg"]
                < c["angle_at_volume_upper_deg"])
        assert 0 < c["pressure_at_volume_pa"] < c["pressure_needed_pa"] * 1.01
        assert c["value_at_pressure"] is None and c["time_needed_s"] is None
        assert c["curve"]["volume_ul"][0] == 0 and c["curve"]["volume_ul"][-1] >= 20 * 0.99


def test_a_time_target_is_the_volume_at_the_flow_rate(shipped_client):
    """45 deg after 8 s at 2.5 ul/s is 45 deg at 20 ul: the same designs, each with the
    time needed (volume / flow) and its band."""
    asked = {"n_results": 2, **BOUNDS}
    by_time = shipped_client.post("/v1/inverse", json={**asked, "target": {
        "kind": "angle_at_time", "time_s": 8, "flow_ul_s": 2.5, "angle_deg": 45}}).json()
    by_volume = shipped_client.post("/v1/inverse", json={**asked, "target": {
        "kind": "angle_at_volume", "volume_ul": 20, "angle_deg": 45}}).json()
    assert by_time["feasible"] and by_time["objective"] == "certainty"
    assert ([c["design"] for c in by_time["candidates"]]
            == [c["design"] for c in by_volume["candidates"]])
    for c in by_time["candidates"]:
        for name in ("needed", "lower", "upper"):
            assert c[f"time_{name}_s"] == pytest.approx(c[f"volume_{name}_ul"] / 2.5)


def test_a_volume_budget_ranks_by_the_volume_needed(emulator):
    """45 deg with no more than 20 ul: every listed design needs at most 20 ul, ranked by
    that volume (the objective "volume"); "margin" ranks by its band's upper end."""
    target = DesignTarget("volume_budget", angle_deg=45.0, volume_ul=20.0)
    bounds = SearchBounds(L_mm=(10, 14), t_mm=(0.6, 1.0), pairs=(("pdms_1_10",
                                                                     "ecoflex_00_30"),))
    res = search_designs(emulator, target, bounds, n_results=3)
    assert res.feasible and res.objective == "volume"
    needed = [c.volume_needed_ul for c in res.candidates]
    assert needed == sorted(needed) and max(needed) <= 20.0
    assert [c.score for c in res.candidates] == pytest.approx(needed, rel=1e-6)
    margin = search_designs(emulator, target, bounds, objective="margin", n_results=3)
    upper = [c.volume_upper_ul for c in margin.candidates]
    assert upper == sorted(upper)


def test_the_flags_of_the_curve_to_the_target_carry_through(emulator):
    """A design past its emulated pressure maximum before the target volume (an
    Ecoflex/Ecoflex design, pinned: one mould) is listed with past_pressure_maximum; one
    that reaches 80 deg at 60 ul past its stretch onset with high_membrane_stretch, named
    in the explanation; a budget's design whose FE range ends before the budget gives no
    angle there and says why.

    The pinned design's pressure maximum is the emulator's, not the FE's: solved by the
    default FE (forty-fourth session) its pressure rises to the 90-deg stop at 55 ul,
    2338 Pa, and it reads 51.9 deg at 26 ul, above the emulator's range here (48 deg, cut
    1 sd short of an early end emulated from its neighbours' curves). The test is of the
    flags' carrying through; the target was 45 deg within 27 ul until the refit on the
    box's faces moved the emulated range's end from 27.3 to 26.9 ul."""
    pinned = {"L_mm": 7.57, "t_mm": 0.71, "T_mm": 0.969, "b_mm": 1.098, "h_mm": 0.147}
    res = search_designs(emulator, DesignTarget("volume_budget", angle_deg=40.0,
                                                volume_ul=26.0),
                         SearchBounds(**{k: (v, v) for k, v in pinned.items()},
                                      pairs=(("ecoflex_00_30", "ecoflex_00_30"),)))
    (c,) = res.candidates
    assert "past_pressure_maximum" in c.curve.validity["flags"]
    assert c.angle_at_volume_deg is not None    # 26 ul is inside its emulated range
    stretched = search_designs(emulator, DesignTarget("angle_at_volume", angle_deg=80.0,
                                                      volume_ul=60.0),
                               SearchBounds(T_mm=(1.8, 2.0), pairs=(("pdms_1_10",
                                                                     "ecoflex_00_30"),)))
    flagged = [c.rank for c in stretched.candidates
               if "high_membrane_stretch" in c.curve.validity["flags"]]
    assert flagged and "(flag high_membrane_stretch)" in stretched.explanation
    small = search_designs(emulator, DesignTarget("volume_budget", angle_deg=85.0,
                                                  volume_ul=60.0),
                           SearchBounds(pairs=(("ecoflex_00_30", "ecoflex_00_30"),)),
                           n_results=2)
    for c in small.candidates:      # 85 deg with ~21 ul: its FE range ends before 60 ul
        assert c.angle_at_volume_deg is None and c.pressure_at_volume_pa is None
        assert any(m.startswith("no angle at 60 ul: the design's FE range ends at")
                   for m in c.curve.validity["messages"])


def test_the_batch_screen_reads_as_one_design_at_a_time(emulator):
    """evaluate_designs_by_volume (the search's screen, many designs in one batch) gives
    what predict_volume and inverse give each design: the means to 1e-6, the bands to
    1e-3 (their variances are computed by different products)."""
    from solver.design_space import PAIRS
    from surrogate.search.space import candidate_design, sobol_candidates

    ranges = SearchBounds().ranges()
    designs = [candidate_design(PAIRS[0], v) for v in sobol_candidates(ranges, None, 3, 16)]
    out = emulator.evaluate_designs_by_volume(designs, 15.0, 40.0)
    for i, d in enumerate(designs):
        at = emulator.predict_volume(d, [15.0])
        inv = emulator.inverse(d, [40.0])
        assert out["angle"][i] == pytest.approx(abs(at.angle_deg[0]), rel=1e-6, nan_ok=True)
        assert out["pressure"][i] == pytest.approx(at.pressure_pa[0], rel=1e-6, nan_ok=True)
        assert out["needed"][i] == pytest.approx(inv.volume_ul[0], rel=1e-6, nan_ok=True)
        assert out["needed_pressure"][i] == pytest.approx(inv.pressure_pa[0], rel=1e-6,
                                                          nan_ok=True)
        if "band_capped_at_fe_range" not in at.validity["flags"]:
            assert out["angle_hi"][i] == pytest.approx(at.upper_deg[0], rel=1e-3,
                                                       nan_ok=True)
        assert out["needed_hi"][i] == pytest.approx(inv.volume_upper_ul[0], rel=1e-3,
                                                    nan_ok=True)
    # a bisection step's screen: the means alone, the same; no band
    means = emulator.evaluate_designs_by_volume(designs, 15.0, 40.0, band=False)
    for key in ("angle", "pressure", "needed", "needed_pressure", "sign"):
        np.testing.assert_allclose(means[key], out[key], rtol=1e-9)
    assert np.isnan(means["angle_lo"]).all() and np.isnan(means["needed_hi"]).all()


@pytest.mark.parametrize("target, field, allowed", [
    ({"kind": "angle_at_volume", "volume_ul": 600, "angle_deg": 45}, "target.volume_ul",
     "500"),
    ({"kind": "angle_at_volume", "angle_deg": 45}, "target.volume_ul", "0 < volume_ul <= 500"),
    ({"kind": "angle_at_volume", "volume_ul": 20, "angle_deg": 45, "pressure_pa": 1500},
     "target.pressure_pa", "takes volume_ul"),
    ({"kind": "angle_at_time", "time_s": 8, "angle_deg": 45}, "target.flow_ul_s",
     "1e-06 <= flow_ul_s <= 1000 ul/s"),
    ({"kind": "angle_at_time", "time_s": 8, "flow_ul_s": 5000, "angle_deg": 45},
     "target.flow_ul_s", "1000"),
    ({"kind": "time_budget", "time_s": 800, "flow_ul_s": 2.5, "angle_deg": 45},
     "target.time_s", "time_s <= 200 s at 2.5 ul/s"),
    ({"kind": "angle_at_pressure", "pressure_pa": 1500, "angle_deg": 45, "flow_ul_s": 2.5},
     "target.flow_ul_s", "takes pressure_pa"),
    ({"kind": "volume_budget", "volume_ul": 20}, "target.angle_deg", "0 < |angle_deg|"),
])
def test_a_pump_target_out_of_range_is_a_problem_naming_the_field(shipped_client, target,
                                                                   field, allowed):
    r = shipped_client.post("/v1/inverse", json={"target": target})
    body = assert_problem(r, 422, field)
    said = [e["allowed"] for e in body["errors"] if e["field"] == field]
    assert any(allowed in a for a in said), said
    assert "/work" not in r.text and "Traceback" not in r.text


def test_a_budget_objective_of_the_other_axis_and_a_model_without_volumes_are_refused(
        shipped_client):
    r = shipped_client.post("/v1/inverse", json={"target": {
        "kind": "volume_budget", "volume_ul": 20, "angle_deg": 45}, "objective": "pressure"})
    assert "volume" in str(assert_problem(r, 422, "objective"))
    r = shipped_client.post("/v1/inverse", json={"model": "paper", "target": {
        "kind": "angle_at_volume", "volume_ul": 20, "angle_deg": 45}})
    assert "gives no injected volume" in str(assert_problem(r, 422, "target.kind"))


def test_the_openapi_page_has_a_volume_target_example(shipped_client):
    schema = shipped_client.get("/openapi.json").json()["components"]["schemas"]
    examples = schema["InverseRequest"]["examples"]
    assert any(e["target"]["kind"] == "volume_budget" for e in examples)
    assert any(e["target"]["kind"] == "angle_at_time" for e in examples)


@pytest.mark.parametrize("argv, words", [
    (["--angle-deg", "45", "--volume-ul", "600"], ("--volume-ul", "0 < --volume-ul <= 500 ul")),
    (["--angle-deg", "45", "--time-s", "8"], ("--flow-ul-s", "1e-06 <= --flow-ul-s <= 1000")),
    (["--angle-deg", "45", "--time-s", "800", "--flow-ul-s", "2.5"],
     ("--time-s", "--time-s <= 200 s at 2.5 ul/s")),
    (["--angle-deg", "45", "--pressure-pa", "1500", "--flow-ul-s", "2.5"],
     ("--flow-ul-s", "does not use --flow-ul-s")),
    (["--angle-deg", "45", "--volume-ul", "20", "--inlet"], ("--inlet", "leave out")),
    (["--kind", "volume_budget", "--angle-deg", "45", "--volume-ul", "20", "--objective",
      "pressure"], ("--objective", "volume | margin")),
])
def test_the_cli_refuses_a_pump_target_out_of_range_in_one_line(capsys, argv, words):
    assert main(["inverse", *argv]) == 2
    _one_line_error(capsys, *words)


def test_the_cli_lists_the_volume_and_time_needed(capsys):
    assert main(["inverse", "--angle-deg", "45", "--time-s", "8", "--flow-ul-s", "2.5",
                 "--pair", PAIR[0], "--L-range", "10", "14", "--t-range", "0.6", "1",
                 "-n", "1"]) == 0
    out = capsys.readouterr().out
    assert "angle_at_time" in out and "v_need_ul" in out and "t_need_s" in out, out
    row = next(line for line in out.splitlines() if line.lstrip().startswith("1 "))
    assert " 20.00 " in row and " 8.00 " in row and " 45.00 " in row, row


def test_a_model_answering_one_design_at_a_time_searches_by_volume_too():
    """The exponential model (no batch screen: each design's predict_volume and inverse,
    the shipped file of format 3 with each family's V(theta)) lists designs that need the
    target volume for the angle, as its own answers give them."""
    from surrogate import load_surrogate

    model = load_surrogate(DATA_DIR / "surrogate.json")
    res = search_designs(model, DesignTarget("angle_at_volume", angle_deg=45.0,
                                             volume_ul=20.0),
                         SearchBounds(pairs=(("pdms_1_15", "ecoflex_00_30"),)), n_results=2)
    assert res.feasible, res.explanation
    for c in res.candidates:
        assert c.volume_needed_ul == pytest.approx(20.0, rel=0.01)
        assert c.volume_lower_ul < 20.0 < c.volume_upper_ul
        assert c.angle_at_volume_deg == pytest.approx(45.0, rel=0.01)
        inv = model.inverse(c.design, [45.0])
        assert c.volume_needed_ul == pytest.approx(inv.volume_ul[0], rel=1e-9)


def test_fewer_designs_than_asked_say_why(capsys):
    """The shipped exponential model, 45 deg at 20 ul, three designs asked: three met the
    target but one was listed, and the explanation read "3 of 4944 evaluated designs meet
    the target; the 1 best by certainty are listed" -- the other two were dropped as
    near-copies of the first (the model varies L and t only: the solves along L from
    neighbouring starts land on one design), unsaid."""
    code = main(["inverse", "--model", "exponential", "--kind", "angle_at_volume",
                 "--angle-deg", "45", "--volume-ul", "20", "-n", "3", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    n_met = int(out["explanation"].split(" of ")[0])
    assert len(out["candidates"]) < min(3, n_met)
    assert "3 were asked for: of the others" in out["explanation"]
    assert "near-copies of a listed design" in out["explanation"]
