"""The HTTP API through TestClient: success and error paths of every endpoint.

Expected numbers come from the fake surrogate (tests/service_fakes.py, the paper's
Eq. 5-6 constants) or from the paper's Table 1 (materials).
"""

from __future__ import annotations

import json
import math

import pytest
from fastapi.testclient import TestClient
from service_fakes import BrokenSurrogate, FakeSurrogate, assert_problem, fast_solve, settings_for

from service.app import create_app

DESIGN = {"L_mm": 7.1, "t_mm": 0.5}


@pytest.fixture
def client(tmp_path):
    app = create_app(settings_for(tmp_path), solve_fn=fast_solve,
                     write_fn=lambda d, s, c: "k" * 32, load_surrogate=False)
    app.state.models.fitted = FakeSurrogate()
    app.state.models.emulator = app.state.models.fitted
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


# -- health and materials ---------------------------------------------------------------

def test_health_reports_what_is_loaded(client):
    body = client.get("/v1/health").json()
    assert body["status"] == "degraded"  # no database yet: /v1/curves answers 503
    assert body["problems"] == ["no curve database curves.h5: /v1/curves answers 503"]
    assert body["surrogate"]["loaded"] and body["surrogate"]["name"] == "fake"
    assert body["database"]["present"] is False
    assert body["jobs"] == {"workers": 1, "running": 0, "queued": 0, "queue_size": 2}


def test_health_without_surrogate_says_why(tmp_path):
    with TestClient(create_app(settings_for(tmp_path))) as c:
        surrogate = c.get("/v1/health").json()["surrogate"]
    assert surrogate["loaded"] is False and surrogate["error"]


def test_materials_lists_the_presets(client):
    items = {m["id"]: m for m in client.get("/v1/materials").json()["items"]}
    assert set(items) == {"pdms_1_10", "pdms_1_15", "ecoflex_00_30"}
    # Table 1: mu0 = (1.241 * 3.034 + 7.879e-9 * 13.02) / 2 = 1.883 kPa for Ecoflex 00-30
    assert items["ecoflex_00_30"]["mu0_kpa"] == pytest.approx(1.883, abs=1e-3)


# -- predict ------------------------------------------------------------------------------

def test_predict_returns_the_surrogates_angles_and_band(client):
    r = client.post("/v1/predict", json={"design": DESIGN, "pressures_pa": [0, 1000, 2000]})
    assert r.status_code == 200, r.text
    body = r.json()
    tau = 731.2 * math.log10(7.179 * 0.5)  # the fake's Eq. 6 (log10 reading)
    expected = [0.101 * 7.1 * math.expm1(p / tau) for p in (0, 1000, 2000)]
    assert body["angle_deg"] == pytest.approx(expected)
    assert body["lower_deg"] == pytest.approx([a - 1 for a in expected])
    assert body["model"] == "emulator" and body["level"] == 0.95
    assert body["design"]["body_length_mm"] == 12.0
    assert body["validity"] == {"in_domain": True, "flags": [], "messages": []}


def test_predict_passes_validity_flags(client):
    r = client.post("/v1/predict", json={"design": DESIGN, "pressures_pa": [3000]})
    assert r.json()["validity"]["flags"] == ["pressure_beyond_fe"]


def test_predict_with_an_inline_custom_material(client):
    design = {**DESIGN, "body_material": {"id": "x", "mu_kpa": [20.0], "alpha": [2.0]}}
    r = client.post("/v1/predict", json={"design": design, "pressures_pa": [100]})
    # the fake covers only pdms_1_10 bodies: a custom body is out of its family
    body = assert_problem(r, 422, "design")
    assert body["type"] == "urn:balloon:problem:out-of-family"
    assert body["errors"][0]["loc"] == ["body", "design"]


@pytest.mark.parametrize("payload, field, allowed", [
    ({"design": {"t_mm": 7}, "pressures_pa": [1]}, "design.t_mm", "0.05 <= t_mm <= 5"),
    ({"design": {"L_mm": 0}, "pressures_pa": [1]}, "design.L_mm", "0.5 <= L_mm <= 60"),
    ({"pressures_pa": [1, -5]}, "pressures_pa.1", "each 0 <= pressures_pa <= 20000"),
    ({"pressures_pa": []}, "pressures_pa", "1-1000 values"),
    ({"pressures_pa": [1], "level": 1.5}, "level", "0.5 <= level <= 0.999"),
    ({"pressures_pa": [1], "colour": "red"}, "colour", None),
    ({}, "pressures_pa", "each 0 <= pressures_pa <= 20000"),
])
def test_predict_refuses_bad_fields_naming_the_range(client, payload, field, allowed):
    body = assert_problem(client.post("/v1/predict", json=payload), 422, field)
    error = next(e for e in body["errors"] if e["field"] == field)
    assert error["loc"][0] == "body"
    if allowed:
        assert allowed in error["allowed"]


def test_predict_refuses_nan_and_malformed_json(client):
    headers = {"content-type": "application/json"}
    r = client.post("/v1/predict", content=b'{"pressures_pa": [NaN]}', headers=headers)
    assert_problem(r, 422, "pressures_pa.0")
    for broken in (b"{not json", b'{"design": {"L_mm": 7.1,}, ', b'{"pressures_pa": [1]} x'):
        problem = assert_problem(client.post("/v1/predict", content=broken, headers=headers),
                                 422, "body")     # the body, not a character offset
        assert problem["errors"][0]["allowed"].startswith("a UTF-8 JSON document")


@pytest.mark.parametrize("design, field", [
    ({"b_mm": 3.5}, "design.b_mm"),                       # chamber wider than the actuator
    ({"body_material": "unobtainium"}, "design.body_material"),
    ({"membrane_material": {"mu_kpa": [1.0], "alpha": [-2.0]}},
     "design.membrane_material.mu_kpa"),                  # mu0 = 1 * -2 / 2 < 0
    ({"chamber_offset_mm": 10.0}, "design.chamber_offset_mm"),  # 10 + 7.1 > 12 mm body
])
def test_predict_domain_errors_name_the_field(client, design, field):
    r = client.post("/v1/predict", json={"design": design, "pressures_pa": [1]})
    body = assert_problem(r, 422, field)
    assert body["errors"][0]["loc"][:2] == ["body", "design"]


def test_predict_model_choice(client):
    r = client.post("/v1/predict", json={"pressures_pa": [1], "model": "nonesuch"})
    assert "nonesuch" in assert_problem(r, 404)["detail"]
    r = client.post("/v1/predict", json={"pressures_pa": [1], "model": "bad name!"})
    assert_problem(r, 422, "model")


def test_predict_without_a_fitted_surrogate_is_503(tmp_path):
    app = create_app(settings_for(tmp_path), load_surrogate=False)
    with TestClient(app) as c:
        r = c.post("/v1/predict", json={"pressures_pa": [1]})
    assert "paper" in assert_problem(r, 503)["detail"]


def test_unexpected_errors_are_500_problems_without_internals(tmp_path):
    app = create_app(settings_for(tmp_path), load_surrogate=False)
    app.state.models.fitted = BrokenSurrogate()
    app.state.models.emulator = app.state.models.fitted
    with TestClient(app, raise_server_exceptions=False) as c:
        r = c.post("/v1/predict", json={"pressures_pa": [1]})
    body = assert_problem(r, 500)
    assert "secret" not in r.text and body["type"].endswith("internal")


# -- plot ---------------------------------------------------------------------------------

def test_plot_is_a_png(client):
    r = client.get("/v1/predict/plot", params={
        "L_mm": 7.1, "t_mm": 0.5, "measured_pressure_pa": [500, 1000],
        "measured_angle_deg": [2, 8]})
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "image/png"
    assert r.content[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_errors(client):
    r = client.get("/v1/predict/plot", params={"measured_pressure_pa": [500]})
    assert_problem(r, 422, "measured_angle_deg")
    assert_problem(client.get("/v1/predict/plot", params={"t_mm": -1}), 422, "t_mm")
    assert_problem(client.get("/v1/predict/plot", params={"body_material": "x"}), 422,
                   "body_material")


# -- inverse ------------------------------------------------------------------------------

def test_inverse_pressure_round_trips_predict(client):
    r = client.post("/v1/inverse/pressure", json={"design": DESIGN, "angles_deg": [10, 45]})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["lower_pa"][1] < body["pressure_pa"][1] < body["upper_pa"][1]
    back = client.post("/v1/predict", json={"design": DESIGN,
                                            "pressures_pa": body["pressure_pa"]}).json()
    assert back["angle_deg"] == pytest.approx([10.0, 45.0])


def test_inverse_pressure_errors(client):
    assert_problem(client.post("/v1/inverse/pressure", json={}), 422, "angles_deg")
    r = client.post("/v1/inverse/pressure", json={"angles_deg": [999]})
    assert "each -360 <= angles_deg <= 360" in assert_problem(r, 422)["errors"][0]["allowed"]
    r = client.post("/v1/inverse/pressure", json={"angles_deg": [-50]})  # below -A
    assert_problem(r, 422, "angles_deg")


def test_inverse_design_with_the_paper_model(client):
    target = {"kind": "angle_at_pressure", "pressure_pa": 1500, "angle_deg": 30}
    r = client.post("/v1/inverse", json={"target": target, "model": "paper",
                                         "L_bounds_mm": [4.1, 15.1], "n_results": 3})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["feasible"] and 1 <= len(body["candidates"]) <= 3
    best = body["candidates"][0]
    assert 4.1 <= best["L_mm"] <= 15.1
    assert best["value_at_pressure"] == pytest.approx(30.0, rel=1e-3)  # meets the target
    # the design it names predicts the target angle at the target pressure
    design = {k: best[k] for k in ("L_mm", "t_mm", "body_material", "membrane_material")}
    back = client.post("/v1/predict", json={"design": design, "pressures_pa": [1500],
                                            "model": "paper"}).json()
    assert back["angle_deg"][0] == pytest.approx(30.0, rel=1e-3)


def test_inverse_design_explains_an_unreachable_target(client):
    target = {"kind": "angle_at_pressure", "pressure_pa": 100, "angle_deg": 300}
    r = client.post("/v1/inverse", json={"target": target, "model": "paper",
                                         "L_bounds_mm": [4, 5]})
    body = r.json()
    assert r.status_code == 200 and body["feasible"] is False and body["candidates"] == []
    # past every curve's end (90 deg): no bound or pressure reaches it, and it says so
    assert "lies past the FE's range" in body["explanation"]
    assert "raise the pressure" not in body["explanation"]


def test_inverse_design_errors(client):
    assert_problem(client.post("/v1/inverse", json={}), 422, "target")
    target = {"kind": "angle_at_pressure", "pressure_pa": 1500, "angle_deg": 30}
    r = client.post("/v1/inverse", json={"target": target, "model": "paper",
                                         "material_pairs": [{"body_material": "pdms_1_15",
                                                             "membrane_material": "pdms_1_15"}]})
    assert_problem(r, 422, "material_pairs")
    r = client.post("/v1/inverse", json={"target": {"pressure_pa": 1500}, "model": "paper"})
    assert_problem(r, 422, "target.angle_deg")  # angle_at_pressure needs an angle
    r = client.post("/v1/inverse", json={"target": target, "L_bounds_mm": [1, 2, 3]})
    assert_problem(r, 422, "L_bounds_mm")


def test_predict_with_the_paper_model_reproduces_table_4(client):
    # Table 4: A = 0.704 at L = 7.1 mm with tau = 420 Pa; the preset must give A within
    # 10 % and (Table 5) tau(0.5 mm) = 412.2 Pa within 3 %: compare the angle at 1000 Pa.
    r = client.post("/v1/predict", json={"design": DESIGN, "pressures_pa": [1000],
                                         "model": "paper"})
    assert r.status_code == 200, r.text
    expected = 0.704 * math.expm1(1000 / 412.2)
    assert r.json()["angle_deg"][0] == pytest.approx(expected, rel=0.12)
    assert r.json()["model"] == "paper"


# -- auth, body limit, CORS, unknown routes -------------------------------------------------

def test_mutating_endpoints_need_the_api_key(client):
    assert_problem(client.post("/v1/solve", json={}), 401)
    r = client.post("/v1/solve", json={}, headers={"X-API-Key": "wrong"})
    assert_problem(r, 403)
    r = client.delete("/v1/jobs/" + "0" * 32)
    assert_problem(r, 401)


def test_mutating_endpoints_are_disabled_without_a_configured_key(tmp_path):
    app = create_app(settings_for(tmp_path, api_key=None), load_surrogate=False)
    with TestClient(app) as c:
        r = c.post("/v1/solve", json={}, headers={"X-API-Key": "anything"})
    assert "BALLOON_API_KEY" in assert_problem(r, 403)["detail"]


def test_body_limit(client):
    big = {"pressures_pa": [1000.0] * 1000, "design": DESIGN, "pad": "x" * 70_000}
    assert_problem(client.post("/v1/predict", json=big), 413)

    def chunks():  # no Content-Length: the limit applies while reading
        yield b'{"pressures_pa": [1], "pad": "'
        for _ in range(100):
            yield b"x" * 1000
        yield b'"}'
    r = client.post("/v1/predict", content=chunks(),
                    headers={"content-type": "application/json"})
    assert assert_problem(r, 413)["type"].endswith(":payload-too-large")   # as announced


def test_a_labs_data_set_is_not_refused_by_the_general_body_limit(client):
    # 600 readings (~95 kB): a lab reading every second fills 64 KiB at ~340 rows, far
    # below the schema's 20,000 (an audit of the thirty-fifth session); one curve only,
    # so the loop refuses it at once (422), after reading the whole body
    rows = [{"curve_id": "s1", "L_mm": 7.1, "t_mm": 0.5, "body_material": "pdms_1_10",
             "membrane_material": "ecoflex_00_30", "time_s": 0.5 * i, "flow_ul_s": 2.5,
             "pressure_pa": 3.0 * i, "angle_deg": 0.1 * i} for i in range(600)]
    r = client.post("/v1/calibrate", json={"rows": rows})
    assert len(r.request.content) > 65_536
    assert_problem(r, 422, "rows.curve_id")
    big = {"rows": rows * 30}                      # 18,000 rows, ~3 MB: within the schema
    assert r.status_code != 413 and client.post("/v1/calibrate", json=big).status_code != 413
    huge = {"rows": rows, "pad": "x" * (5 * 2**20)}
    assert_problem(client.post("/v1/calibrate", json=huge), 413)


def test_cors_is_off_by_default_and_configurable(client, tmp_path):
    preflight = {"Origin": "https://lab.example", "Access-Control-Request-Method": "POST"}
    r = client.options("/v1/predict", headers=preflight)
    assert "access-control-allow-origin" not in r.headers
    app = create_app(settings_for(tmp_path, cors_origins=["https://lab.example"]),
                     load_surrogate=False)
    with TestClient(app) as c:
        r = c.options("/v1/predict", headers=preflight)
        assert r.headers["access-control-allow-origin"] == "https://lab.example"
        r = c.options("/v1/predict", headers={**preflight, "Origin": "https://evil.example"})
        assert r.status_code == 400


def test_unknown_route_and_method_are_problems(client):
    assert_problem(client.get("/v1/nothing"), 404)
    assert_problem(client.put("/v1/predict"), 405)


def test_openapi_has_an_example_for_every_request_body(client):
    spec = client.get("/openapi.json").json()
    schemas = spec["components"]["schemas"]
    for path, ops in spec["paths"].items():
        for op in ops.values():
            ref = (op.get("requestBody", {}).get("content", {}).get("application/json", {})
                   .get("schema", {}).get("$ref"))
            if ref:  # an example of the whole body, or of its fields
                schema = schemas[ref.split("/")[-1]]
                assert schema.get("examples") or any(
                    "examples" in prop for prop in schema["properties"].values()), path


def test_saved_models_hook(client, monkeypatch):
    """Names other than fitted/paper go to surrogate.calibration.load_model (one hook)."""
    import service.models

    class PredictOnly:  # like a calibrated model: predicts, does not invert
        predict = FakeSurrogate.predict
        _params = FakeSurrogate._params

    monkeypatch.setattr(service.models, "load_calibrated", lambda name, d, design_space=None:
                        PredictOnly())
    r = client.post("/v1/predict", json={"pressures_pa": [0], "model": "lab1"})
    assert r.status_code == 200 and r.json()["model"] == "lab1"
    r = client.post("/v1/inverse/pressure", json={"angles_deg": [10], "model": "lab1"})
    assert_problem(r, 422, "model")
    target = {"pressure_pa": 1500, "angle_deg": 30}
    assert_problem(client.post("/v1/inverse", json={"target": target, "model": "lab1"}), 422,
                   "model")


def test_a_damaged_saved_model_is_503(client):
    models_dir = client.app.state.settings.models_dir
    models_dir.mkdir(parents=True, exist_ok=True)
    (models_dir / "broken.json").write_text("{not json")
    r = client.post("/v1/predict", json={"pressures_pa": [0], "model": "broken"})
    assert_problem(r, 503)


def test_calibrate_save_name_errors_name_the_save_field(client):
    from service.routes.calibration import EXAMPLE_ROWS

    def calibrate(save):
        return client.post("/v1/calibrate", headers={"X-API-Key": "test-key"},
                           json={"rows": EXAMPLE_ROWS, "model": "paper", "save": save})

    assert_problem(calibrate("../lab"), 422, "save")  # a name, never a path
    for builtin in ("paper", "emulator", "exponential", "fitted"):   # never choosable
        assert "not 'emulator', 'exponential', 'fitted', 'paper'" in assert_problem(
            calibrate(builtin), 422, "save")["errors"][0]["allowed"]
    assert calibrate("lab1").json()["saved_model"] == "lab1"
    body = assert_problem(calibrate("lab1"), 409)  # never overwrites a model
    assert body["model"] == "lab1" and "'lab1' already exists" in body["detail"]


def test_a_force_target_is_met_across_the_box_by_the_shipped_emulator(shipped_client):
    # issue 14: "force targets work": 0.2 mN at 1500 Pa with the blocked tip, searched over
    # the whole box; every candidate's own prediction gives that force, with its band
    target = {"kind": "force_at_pressure", "pressure_pa": 1500, "force_mn": 0.2}
    r = shipped_client.post("/v1/inverse", json={"target": target, "n_results": 3})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["model"] == "emulator" and body["feasible"], body["explanation"]
    for c in body["candidates"]:
        keys = ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "body_material", "membrane_material")
        design = {k: c[k] for k in keys if k in c}
        back = shipped_client.post("/v1/predict", json={"design": design,
                                                        "pressures_pa": [1500]}).json()
        f, lo, hi = back["force_mn"][0], back["force_lower_mn"][0], back["force_upper_mn"][0]
        assert f is not None and lo <= f <= hi
        assert f == pytest.approx(0.2, rel=0.05)


@pytest.mark.parametrize(("extra", "field", "allowed"), [
    ({"folds": 1}, "folds", "2 <= folds <= 50"),
    ({"strict": "yes"}, "strict", "true or false"),
    ({"model": "m" * 65}, "model", "1-64 characters"),
])
def test_calibrate_validation_errors_state_the_allowed_range(client, extra, field, allowed):
    from service.routes.calibration import EXAMPLE_ROWS

    r = client.post("/v1/calibrate", json={"rows": EXAMPLE_ROWS, "model": "paper", **extra})
    assert assert_problem(r, 422, field)["errors"][0]["allowed"] == allowed


def test_a_measured_cell_is_not_read_as_the_request_field_of_its_name(client):
    """A NaN pressure in a measured row: the cell's rule, not an inverse target's range
    (it said "0 < pressure_pa <= 20000", while rows take -1e5..1e6 Pa)."""
    from service.routes.calibration import EXAMPLE_ROWS

    text = json.dumps({"rows": EXAMPLE_ROWS, "model": "paper"}).replace(
        '"pressure_pa": 400', '"pressure_pa": NaN', 1)
    r = client.post("/v1/calibrate", content=text.encode(),
                    headers={"content-type": "application/json"})
    error = assert_problem(r, 422, "rows.1.pressure_pa")["errors"][0]
    assert error["allowed"].startswith("a finite number") and "20000" not in error["allowed"]


def test_a_material_pair_may_be_written_body_slash_membrane(client):
    # as the CLI's --pair and the answer's best_reachable write it; before, a string was
    # "Input should be a valid dictionary" (an audit of the thirty-fifth session)
    target = {"kind": "angle_at_pressure", "pressure_pa": 1500, "angle_deg": 30}
    text = client.post("/v1/inverse", json={"target": target, "model": "paper", "n_results": 1,
                                            "material_pairs": ["pdms_1_10/ecoflex_00_30"]})
    assert text.status_code == 200, text.text
    best = text.json()["candidates"][0]
    assert (best["body_material"], best["membrane_material"]) == ("pdms_1_10", "ecoflex_00_30")
    r = client.post("/v1/inverse", json={"target": target, "model": "paper",
                                         "material_pairs": ["pdms_1_10"]})
    problem = assert_problem(r, 422, "material_pairs.0")
    assert "'pdms_1_10' is not of this form" == problem["errors"][0]["message"]
    assert "body/membrane" in problem["errors"][0]["allowed"]   # the form, said once
    assert "Value error" not in problem["detail"]


@pytest.mark.parametrize(("path", "body", "field", "meant"), [
    ("/v1/predict", {"design": {"L_mm": 7.1, "t_mm": 0.5}, "pressure_pa": [1000]},
     "pressure_pa", "pressures_pa"),
    ("/v1/predict", {"design": {"L": 7.1, "t_mm": 0.5}, "pressures_pa": [1000]},
     "design.L", "L_mm"),
    ("/v1/inverse", {"target": {"kind": "angle_at_pressure", "pressure": 1500,
                                "angle_deg": 30}}, "target.pressure", "pressure_pa"),
])
def test_an_unknown_field_is_answered_with_the_field_meant(client, path, body, field, meant):
    problem = assert_problem(client.post(path, json=body), 422, field)
    entry = next(e for e in problem["errors"] if e["field"] == field)
    assert f"did you mean {meant!r}" in entry["message"]
