"""Hostile requests of the thirtieth session: a material that is not a preset was told
under the names of pydantic's union branches ("design.body_material.constrained-str",
"...MaterialIn.id") with both branches' errors and a regular expression for the range;
a text field not of its form (a model's name, a curves filter, a name to save) stated the
pattern, or "at most 64 characters", instead of the form in words; a saved model could
take a built-in model's name in another case ("Emulator") or one differing only in case
from a saved model's (one file on a case-insensitive file system)."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for

from service.app import create_app

KEY = {"X-API-Key": "test-key"}
ROWS = [{"curve_id": "c1", "L_mm": 7.1, "t_mm": 0.5, "body_material": "pdms_1_10",
         "membrane_material": "ecoflex_00_30", "pressure_pa": 500.0, "angle_deg": 5.0}]


@pytest.fixture
def client(tmp_path):
    app = create_app(settings_for(tmp_path), load_surrogate=False)
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


def _predict(client, material) -> dict:
    r = client.post("/v1/predict", json={"design": {"body_material": material},
                                         "pressures_pa": [1000], "model": "paper"})
    return assert_problem(r, 422)


def _no_union_branch(body: dict) -> None:
    for word in ("constrained-str", "MaterialIn", "should match pattern", "^[A-Za-z"):
        assert word not in str(body), body


def test_a_material_id_not_of_the_form_is_one_error_at_the_field_with_the_presets(client):
    body = _predict(client, "pdms\x00")
    _no_union_branch(body)
    assert [e["field"] for e in body["errors"]] == ["design.body_material"]
    assert "pdms_1_10" in body["errors"][0]["allowed"]
    assert "<preset>*<scale>" in body["errors"][0]["allowed"]


def test_an_inline_materials_bad_key_is_told_at_its_own_field(client):
    body = _predict(client, {"id": "mine", "mu_kpa": [1.0], "alpha": [3.0], "nu": 0.5})
    _no_union_branch(body)
    assert [e["field"] for e in body["errors"]] == ["design.body_material.nu"]


def test_an_inline_materials_id_not_of_the_form_states_the_form_in_words(client):
    body = _predict(client, {"id": "\u202e", "mu_kpa": [1.0], "alpha": [3.0]})
    _no_union_branch(body)
    (error,) = body["errors"]
    assert error["field"] == "design.body_material.id"
    assert "1-64 letters, digits" in error["allowed"]


@pytest.mark.parametrize("material", [5, None, ["pdms_1_10"]])
def test_a_material_that_is_neither_text_nor_an_object_is_one_error(client, material):
    body = _predict(client, material)
    _no_union_branch(body)
    (error,) = body["errors"]
    assert error["field"] == "design.body_material" and "pdms_1_10" in error["allowed"]
    assert "{id, mu_kpa, alpha}" in error["message"]


def test_a_model_name_not_of_the_form_names_the_built_in_models(client):
    r = client.post("/v1/predict", json={"design": {}, "pressures_pa": [1000],
                                         "model": "../../etc/passwd"})
    body = assert_problem(r, 422, "model")
    _no_union_branch(body)
    assert "emulator" in body["errors"][0]["allowed"]


def test_a_curves_filter_not_of_the_form_states_it_without_echoing_a_long_value(client):
    r = client.get("/v1/curves", params={"body_material": "x" * 5000 + "\x00"})
    body = assert_problem(r, 422, "body_material")
    _no_union_branch(body)
    assert len(body["detail"]) < 400 and "pdms_1_10" in body["errors"][0]["allowed"]


def test_a_save_name_not_of_the_form_states_the_rule_not_just_its_length(client):
    r = client.post("/v1/calibrate", headers=KEY, json={"rows": ROWS, "save": "a b"})
    body = assert_problem(r, 422, "save")
    assert "letters, digits" in body["errors"][0]["allowed"]


@pytest.mark.parametrize("name", ["Emulator", "PAPER", "Fitted", "exponentiaL"])
def test_a_built_in_models_name_in_another_case_cannot_be_saved(client, name):
    r = client.post("/v1/calibrate", headers=KEY, json={"rows": ROWS, "save": name})
    body = assert_problem(r, 422, "save")
    assert "in any case" in body["errors"][0]["allowed"]
    assert not list(client.app.state.settings.models_dir.glob("*.json"))


def saved_and_no_work(client, monkeypatch, name: str):
    """The models directory with a saved (empty) model ``name``; a calibration that fails
    the test if it runs: the name must be refused before the work."""
    models = client.app.state.settings.models_dir
    models.mkdir(parents=True, exist_ok=True)
    (models / f"{name}.json").write_text("{}")
    monkeypatch.setattr("surrogate.calibration.run_calibration",
                        lambda *a, **k: pytest.fail("calibrated before checking the name"))
    return models


def test_a_name_differing_only_in_case_from_a_saved_model_is_409_before_the_work(
        client, monkeypatch):
    models = saved_and_no_work(client, monkeypatch, "Lab1")
    r = client.post("/v1/calibrate", headers=KEY, json={"rows": ROWS, "save": "lab1"})
    body = assert_problem(r, 409)
    assert "'Lab1' already exists" in body["detail"] and "only in case" in body["detail"]
    assert body["model"] == "Lab1"         # the saved one, as docs/service.md says
    assert str(models) not in r.text
    assert (models / "Lab1.json").read_text() == "{}" and not (models / "lab1.json").exists()


def test_a_taken_name_is_409_before_the_work(client, monkeypatch):
    saved_and_no_work(client, monkeypatch, "lab1")
    r = client.post("/v1/calibrate", headers=KEY, json={"rows": ROWS, "save": "lab1"})
    body = assert_problem(r, 409)
    assert "'lab1' already exists" in body["detail"] and body["model"] == "lab1"


@pytest.mark.parametrize(("content_type", "named"), [
    ("text/plain", "'text/plain'"),
    ("application/x-www-form-urlencoded", "'application/x-www-form-urlencoded'"),  # curl -d
    (None, "no Content-Type"),
])
def test_a_json_body_sent_as_another_media_type_is_told_so(client, content_type, named):
    headers = {"content-type": content_type} if content_type else {}
    r = client.post("/v1/predict", headers=headers,
                    content=b'{"design": {}, "pressures_pa": [1000], "model": "paper"}')
    body = assert_problem(r, 422, "body")
    assert named in body["detail"] and body["errors"][0]["allowed"] == (
        "Content-Type: application/json")


@pytest.mark.parametrize(("path", "range_header", "status"), [
    ("/static/explorer/js/app.js", "bytes=999999999-", 416),   # past the file's end
    ("/static/explorer/js/app.js", "bytes=abc", 400),
    ("/", "bytes=999999999-", 416),
])
def test_a_range_a_file_cannot_serve_is_a_problem_document(client, path, range_header,
                                                           status):
    r = client.get(path, headers={"Range": range_header})
    assert_problem(r, status)
    if status == 416:
        assert r.headers["content-range"].startswith("bytes */")


def test_a_range_a_file_can_serve_is_served(client):
    r = client.get("/static/explorer/js/app.js", headers={"Range": "bytes=0-9"})
    assert r.status_code == 206 and len(r.content) == 10
