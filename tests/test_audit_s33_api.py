"""The thirty-third session's API audit (a new lab user's findings): the README's solve
stored a coarse hex1 curve that the plot then drew as "FE"; /v1/curves said -0.0 deg for
curves that ran to -94; the force was flagged too wide (and counted in "pressure(s)") at
volumes past the FE's range; a past-range message gave two end angles, unsigned for a
pair that bends negative; a reversed material order was offered a pair that bends the
other way; an out-of-box design was refused one field per request; CLI errors named
Python fields, and a missing --model file "no saved model"; the legacy model name in
errors; the plot refused W_mm; in_domain false for in-box designs with a point past the
range; bands below zero; the plot's title without T/b/h; `balloon solve --tip blocked`
without the force; fe_limit_volume_ul missing by pressure."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from service_fakes import make_curve

from service.cli import main
from solver.design import Design
from solver.settings import SolverSettings

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
REVERSED = {"L_mm": 9, "t_mm": 0.7, "body_material": "ecoflex_00_30",
            "membrane_material": "pdms_1_15"}


def _ok(response) -> dict:
    assert response.status_code == 200, response.text
    return response.json()


def _no_negative_zero(values) -> None:
    for v in values:
        assert v is None or v != 0 or math.copysign(1.0, v) > 0, values


# -- 3: the solve example stores a real curve; a non-default curve is labelled ------------
def test_the_solve_examples_use_the_default_element():
    from service.schemas.jobs import SolveRequest

    snippet = (ROOT / "docs" / "snippets" / "solve.sh").read_text()
    assert "hex1" not in snippet and "max_angle_deg" not in snippet
    for example in SolveRequest.model_config["json_schema_extra"]["examples"]:
        assert example.get("settings", {}).get("element", "hex2") == "hex2"


def test_a_stored_curve_of_other_settings_is_labelled_with_them_and_a_blocked_tip_left_out(
        tmp_path):
    from service.plotting import nearby_curves, settings_note
    from solver.store import CurveStore, make_record

    assert settings_note(SolverSettings().as_dict()) == ""
    with CurveStore(tmp_path / "c.h5", mode="a") as db:
        db.put(make_record(Design(L_mm=7.2), SolverSettings(element="hex1",
                                                            max_angle_deg=10), make_curve()))
        db.put(make_record(Design(L_mm=7.1), SolverSettings(), make_curve()))
        db.put(make_record(Design(L_mm=7.1), SolverSettings(tip="blocked"), make_curve()))
    labels = [label for label, _, _ in nearby_curves(tmp_path / "c.h5", Design(), 5, 2000)]
    assert len(labels) == 2, labels          # the blocked tip's angle is not the free tip's
    assert "FE L=7.1 mm, t=0.5 mm" in labels
    (coarse,) = [x for x in labels if "7.2" in x]
    assert "hex1" in coarse and "stopped at 10 deg" in coarse


# -- 4: /v1/curves' max_angle_deg is the signed extreme -----------------------------------
def test_curves_list_the_signed_extreme_angle_of_a_reversed_pair(shipped_client):
    from service.routes.curves import _peak

    assert _peak([0.0, -1.0, -94.0]) == -94.0 and _peak([-0.0, 3.0, 90.1]) == 90.1
    page = _ok(shipped_client.get("/v1/curves", params={
        "body_material": "ecoflex_00_30", "membrane_material": "pdms_1_15", "limit": 20,
        "status": "complete"}))
    assert page["items"]
    assert all(item["max_angle_deg"] < -45 for item in page["items"]), page["items"]


# -- 6: force flags at volumes past the FE's range ----------------------------------------
def test_volumes_past_the_range_are_force_past_fe_range_in_volumes(shipped_client):
    body = _ok(shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 9, "t_mm": 0.7, "body_material": "ecoflex_00_30",
                   "membrane_material": "ecoflex_00_30"},
        "volumes_ul": [60, 80, 100, 150, 190, 200, 600]}))
    v = body["validity"]
    assert body["angle_deg"][-1] is None and "force_past_fe_range" in v["flags"]
    assert "force_band_too_wide" not in v["flags"], v     # the two past points are not that
    assert not any("pressure(s)" in m for m in v["messages"]), v["messages"]


# -- 8, 9: one end angle, signed ----------------------------------------------------------
def test_the_past_range_message_states_the_one_end_angle(shipped_client):
    body = _ok(shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 9.3, "t_mm": 0.83, "T_mm": 1.4, "b_mm": 2.1, "h_mm": 0.22},
        "pressures_pa": [500, 2700]}))
    v = body["validity"]
    (message,) = [m for m in v["messages"] if "past the FE's range" in m]
    assert f"ends at {v['fe_limit_angle_deg']:.1f} deg" in message
    assert "+-" not in message and "+-" not in v["fe_stop_reason"]


def test_the_fe_limit_angle_of_a_pair_bending_negative_is_negative(shipped_client):
    body = _ok(shipped_client.post("/v1/predict", json={
        "design": REVERSED, "pressures_pa": [0, 500, 2000, 3000]}))
    v = body["validity"]
    assert v["fe_limit_angle_deg"] < 0 and body["angle_deg"][-1] is None
    (message,) = [m for m in v["messages"] if "past the FE's range" in m]
    assert f"ends at {v['fe_limit_angle_deg']:.1f} deg" in message
    inverse = _ok(shipped_client.post("/v1/inverse/pressure", json={
        "design": REVERSED, "angles_deg": [-30]}))
    assert inverse["validity"]["fe_limit_angle_deg"] == pytest.approx(v["fe_limit_angle_deg"])


# -- 10, 11: the out-of-box refusal -------------------------------------------------------
def test_a_reversed_material_order_is_offered_a_pair_that_bends_the_same_way(shipped_client):
    from solver.design_space import pair_bending_alike

    r = shipped_client.post("/v1/predict", json={
        "design": {"body_material": "ecoflex_00_30", "membrane_material": "pdms_1_10"},
        "pressures_pa": [1000]})
    assert r.status_code == 422 and r.json()["type"].endswith("out-of-box")
    assert "ecoflex_00_30/pdms_1_15" in r.json()["detail"]
    assert "same way" in r.json()["detail"]
    assert pair_bending_alike("pdms_1_15", "pdms_1_10")[0] == ("ecoflex_00_30", "pdms_1_15")
    assert pair_bending_alike("pdms_1_10", "pdms_1_15")[0] == ("pdms_1_15", "ecoflex_00_30")


def test_every_field_outside_the_box_is_named_in_one_refusal(shipped_client):
    r = shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5, "W_mm": 6}, "pressures_pa": [1000]})
    assert r.status_code == 422
    fields = [e["field"] for e in r.json()["errors"]]
    assert fields == ["design.L_mm", "design.t_mm", "design.T_mm", "design.b_mm",
                      "design.h_mm"]
    assert all(e["allowed"] for e in r.json()["errors"])
    assert "defaults of T, b and h" in README and "do not" in README


def test_each_fields_range_stands_beside_it_in_the_refusals_sentence(shipped_client):
    # the first field's range came last, after the nearest design and the FE offer, where
    # it read as the offer's (an audit of the thirty-fifth session)
    r = shipped_client.post("/v1/predict", json={"design": {"L_mm": 25, "t_mm": 0.3},
                                                 "pressures_pa": [1000]})
    detail = r.json()["detail"]
    ranges = {e["field"]: e["allowed"] for e in r.json()["errors"]}
    at = {f: detail.index(f"(allowed: {a})") for f, a in ranges.items()}
    assert at["design.L_mm"] < detail.index("also") < at["design.t_mm"]
    assert at["design.t_mm"] < detail.index("the nearest design") < detail.index("POST /v1/solve")
    assert detail.count("(allowed:") == 2


# -- 12, 13: the CLI names the option typed -----------------------------------------------
@pytest.mark.parametrize(("argv", "option"), [
    (["predict", "--L-mm", "7.1", "--t-mm", "99", "--pressures", "1000"], "--t-mm"),
    (["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--body-material", "rubber",
      "--pressures", "1000"], "--body-material"),
    (["solve", "--t-mm", "99", "--quiet"], "--t-mm"),
    (["solve", "--mesh", "9", "--quiet"], "--mesh"),
    (["solve", "--max-angle-deg", "0", "--quiet"], "--max-angle-deg"),
])
def test_cli_errors_name_the_option(argv, option, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"balloon: error: {option}: "), err
    assert len(err.strip().splitlines()) == 1


def test_fit_names_its_db_option(tmp_path, capsys):
    bad = tmp_path / "bad.h5"
    bad.write_text("not hdf5")
    assert main(["fit", "--db", str(bad), "-o", str(tmp_path / "s.json")]) == 2
    assert capsys.readouterr().err.startswith("balloon: error: --db: ")


def test_a_model_path_that_does_not_exist_is_file_not_found(tmp_path, capsys):
    missing = tmp_path / "nope.json"
    assert main(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "1000",
                 "--model", str(missing)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("balloon: error: --model: ") and "file not found" in err
    assert "no saved model" not in err


def test_the_out_of_box_refusal_on_the_cli_names_every_option():
    from service.commands.predict import as_flag
    from solver.design_space import OutOfBoxError, locate

    with pytest.raises(OutOfBoxError) as info:
        locate(Design(W_mm=6.0))
    text = str(as_flag(info.value))
    assert text.startswith("--L-mm: ")
    for option in ("--t-mm", "--T-mm", "--b-mm", "--h-mm"):
        assert f"also {option}: " in text


# -- 14: current model names only ---------------------------------------------------------
def test_errors_offer_the_current_model_names_only(shipped_client):
    from service.errors import FieldError
    from service.models import require

    with pytest.raises(FieldError) as info:
        require(object(), "lab1", "inverse")
    assert "emulator" in info.value.allowed and "exponential" in info.value.allowed
    assert "fitted" not in info.value.allowed
    r = shipped_client.post("/v1/predict", json={"pressures_pa": [1], "model": "lab9"})
    assert r.status_code == 404 and "fitted" not in r.json()["detail"]
    r = shipped_client.post("/v1/predict", json={"pressures_pa": [1], "model": "../x"})
    assert r.status_code == 422 and "fitted" not in r.json()["errors"][0]["allowed"]


# -- 16: the plot takes W_mm --------------------------------------------------------------
def test_the_plot_takes_the_width_as_predict_does(shipped_client):
    r = shipped_client.get("/v1/predict/plot", params={
        "W_mm": 6, "L_mm": 14.2, "t_mm": 1, "T_mm": 2, "b_mm": 3.6, "h_mm": 0.3})
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "image/png"


# -- 22, 23, 24: the docs say what the code does ------------------------------------------
def test_the_stiffness_box_is_the_ratio_the_emulator_checks(shipped_client, capsys):
    from solver.design_space import REDUCED_RATIO_RANGE

    lo, hi = REDUCED_RATIO_RANGE
    _ok(shipped_client.post("/v1/predict", json={
        "design": {"membrane_material": "ecoflex_00_30*3"}, "pressures_pa": [500]}))
    r = shipped_client.post("/v1/predict", json={
        "design": {"membrane_material": "ecoflex_00_30*5"}, "pressures_pa": [500]})
    assert r.status_code == 422 and f"{lo:g} <= s_body / s_membrane <= {hi:g}" in r.text
    assert "stiffness scaled 0.5-2" not in README and f"{lo:g}-{hi:g}" in README
    with pytest.raises(SystemExit):
        main(["predict", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert f"{lo:g}..{hi:g}" in help_text and "0.5..2" not in help_text


def test_service_doc_lists_the_out_of_box_problem_and_the_emulator_path():
    text = (ROOT / "docs" / "service.md").read_text()
    assert "`BALLOON_EMULATOR_PATH`" in text and "`out-of-box`" in text


def test_readme_says_which_models_take_inline_materials():
    assert "or inline Ogden constants." not in README
    said = " ".join(README.split())
    assert "inline Ogden constants (`{\"id\", \"mu_kpa\", \"alpha\"}`) are taken by the FE" in said


# -- 27: in_domain is about the design ----------------------------------------------------
@pytest.mark.parametrize("model", ["emulator", "exponential"])
def test_in_domain_stays_true_for_an_in_box_design_with_a_point_past_the_range(
        shipped_client, model):
    body = _ok(shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 9, "t_mm": 0.7, "T_mm": 1.4, "b_mm": 2, "h_mm": 0.2}
        if model == "emulator" else {"L_mm": 7.1, "t_mm": 0.5},
        "pressures_pa": [500, 1000, 20000], "model": model}))
    assert body["angle_deg"][-1] is None and "past_fe_range" in body["validity"]["flags"]
    assert body["validity"]["in_domain"] is True


def test_in_domain_is_false_for_a_design_outside_the_exponential_models_ranges(
        shipped_client):
    body = _ok(shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 20, "t_mm": 0.5}, "pressures_pa": [500], "model": "exponential"}))
    assert body["validity"]["in_domain"] is False


# -- 28: no band across zero, no -0.0 -----------------------------------------------------
def test_bands_do_not_cross_zero_for_a_design_that_bends_one_way(shipped_client):
    exp = _ok(shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5}, "pressures_pa": [0, 500, 1000],
        "model": "exponential"}))
    assert min(exp["lower_deg"]) >= 0.0
    em = _ok(shipped_client.post("/v1/predict", json={"pressures_pa": [0, 25, 500]}))
    assert min(em["lower_deg"]) >= 0.0
    assert min(f for f in em["force_lower_mn"] if f is not None) >= 0.0
    rev = _ok(shipped_client.post("/v1/predict", json={"design": REVERSED,
                                                       "pressures_pa": [0, 25, 1000]}))
    assert max(rev["upper_deg"]) <= 0.0
    assert max(f for f in rev["force_upper_mn"] if f is not None) <= 0.0
    for body in (exp, em, rev):
        for key in ("angle_deg", "lower_deg", "upper_deg", "force_mn", "force_lower_mn",
                    "force_upper_mn"):
            _no_negative_zero(body.get(key) or [])


def test_one_signed_floors_caps_and_drops_negative_zero():
    from surrogate.predictor import one_signed

    a, lo, hi = one_signed(np.array([0.0, 1.0, np.nan]), np.array([-0.1, 0.5, np.nan]),
                           np.array([0.1, 1.5, np.nan]), +1)
    assert lo.tolist()[:2] == [0.0, 0.5] and np.isnan(lo[2])
    a, lo, hi = one_signed(np.array([-0.0]), np.array([-0.1]), np.array([0.1]), -1)
    assert hi[0] == 0.0 and math.copysign(1.0, hi[0]) > 0 and math.copysign(1.0, a[0]) > 0


# -- 29: the plot's title and domain note -------------------------------------------------
def _title_of(prediction: dict) -> tuple[str, int]:
    from service.plotting import _figure, _title

    ax = _figure().add_subplot()
    _title(ax, prediction)
    return ax.get_title(), len(ax.texts)


def test_the_plot_title_names_the_whole_design_and_the_domain_only_when_outside(
        shipped_client):
    pred = _ok(shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 9.1, "t_mm": 0.6}, "pressures_pa": [500, 4000]}))
    title, texts = _title_of(pred)
    for part in ("L = 9.1", "t = 0.6", "T = 1", "b = 1.8", "h = 0.15", "W = 3",
                 "pdms_1_10 / ecoflex_00_30"):
        assert part in title, title
    assert "outside" not in title and texts == 0    # in the box, a point past the range
    out = _ok(shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 20, "t_mm": 0.5}, "pressures_pa": [500], "model": "exponential"}))
    title, texts = _title_of(out)
    assert "outside the model's fitted domain: L_outside_fitted_range" in title and texts == 0


# -- 30: `balloon solve --tip blocked` ----------------------------------------------------
def test_a_blocked_solve_prints_the_force_and_its_progress_is_not_in_degrees():
    from service.commands.solve import progress_bar, table

    curve = make_curve()
    head = table(curve, with_force=True).splitlines()[0]
    assert head.split()[-1] == "force_mn"
    assert "force_mn" not in table(curve, with_force=False)
    bar, on_step = progress_bar(SolverSettings(tip="blocked", max_pressure_pa=2500), False)
    assert bar.total == 100 and bar.unit == "%"
    on_step({"angle_deg": 0.0, "pressure_pa": 1250.0, "volume_ul": 1.0, "step": 3})
    assert bar.n == 50
    bar.close()
    free, _ = progress_bar(SolverSettings(), False)
    assert free.unit == "deg" and free.total == 90
    free.close()


# -- 31: fe_limit_volume_ul wherever volume is given --------------------------------------
def test_the_fe_limit_volume_is_given_by_pressure_and_by_the_inverse(shipped_client):
    for model in ("emulator", "exponential"):
        body = _ok(shipped_client.post("/v1/predict", json={
            "design": {"L_mm": 7.1, "t_mm": 0.5}, "pressures_pa": [500], "model": model}))
        assert body["volume_ul"] and body["validity"]["fe_limit_volume_ul"] > 0, model
    inverse = _ok(shipped_client.post("/v1/inverse/pressure", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5}, "angles_deg": [45]}))
    assert inverse["volume_ul"] and inverse["validity"]["fe_limit_volume_ul"] > 0
    assert json.dumps(inverse)   # plain JSON


def test_a_field_a_design_does_not_take_is_refused_with_how_to_say_it(shipped_client):
    """``body_stiffness_scale`` (the CLI's option) in an HTTP design was "Extra inputs are
    not permitted" and no hint; a refused field quoted a range of its own (an audit of
    2026-12-06)."""
    client = shipped_client
    r = client.post("/v1/predict", json={"design": {"L_mm": 7.1, "body_stiffness_scale": 1.2},
                                         "pressures_pa": [500]})
    assert r.status_code == 422
    err = r.json()["errors"][0]
    assert err["field"] == "design.body_stiffness_scale"
    assert '"pdms_1_10*1.2"' in err["allowed"]
    r = client.post("/v1/predict", json={"design": {"L_mm": 7.1, "colour": "red"},
                                         "pressures_pa": [500]})
    assert "leave it out" in r.json()["errors"][0]["allowed"]


@pytest.mark.parametrize(("typed", "meant"), [("ecoflex_0030", "ecoflex_00_30"),
                                              ("Ecoflex_00_30", "ecoflex_00_30"),
                                              ("pdms_1-10*1.2", "pdms_1_10")])
def test_a_mistyped_material_is_answered_with_the_preset_meant(shipped_client, typed, meant):
    r = shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 7.1, "t_mm": 0.5, "membrane_material": typed},
        "pressures_pa": [1000]})
    assert f"did you mean {meant!r}" in r.json()["detail"]
