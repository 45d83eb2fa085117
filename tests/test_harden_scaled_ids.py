"""A scaled preset ("ecoflex_00_30*1.5": every mu_kpa times 1.5) is a material wherever a
material id is asked: the plot's query, the curve list's filter (the database stores such
ids), and inverse design's pairs, where it is refused by what it means, not by a pattern
(the box's stiffness scales are searched within their bounds)."""

from __future__ import annotations


def test_the_plot_takes_a_scaled_preset(shipped_client):
    r = shipped_client.get("/v1/predict/plot", params={"membrane_material": "ecoflex_00_30*1.5",
                                                       "nearby": 0})
    assert r.status_code == 200 and r.content[:4] == b"\x89PNG"


def test_the_curve_list_filters_by_a_stored_scaled_id(shipped_client):
    stored = next(i["body_material"] for i in shipped_client.get(
        "/v1/curves", params={"limit": 20}).json()["items"] if "*" in i["body_material"])
    page = shipped_client.get("/v1/curves", params={"body_material": stored}).json()
    assert page["total"] >= 1
    assert {i["body_material"] for i in page["items"]} == {stored}


def test_inverse_design_refuses_a_scaled_pair_saying_where_scales_go(shipped_client):
    r = shipped_client.post("/v1/inverse", json={
        "target": {"kind": "angle_at_pressure", "pressure_pa": 1500, "angle_deg": 45},
        "material_pairs": [{"body_material": "pdms_1_10*1.5",
                            "membrane_material": "ecoflex_00_30"}]})
    assert r.status_code == 422
    problem = r.json()
    assert problem["errors"][0]["field"] == "material_pairs"
    assert "body_stiffness_scale_bounds" in problem["detail"]


def test_a_scale_the_material_limits_refuse_names_the_layer(shipped_client):
    r = shipped_client.post("/v1/predict", json={
        "design": {"membrane_material": "ecoflex_00_30*1e308"}, "pressures_pa": [500]})
    assert r.status_code == 422
    error = r.json()["errors"][0]
    assert error["field"] == "design.membrane_material" and "1e6 kPa" in error["allowed"]
