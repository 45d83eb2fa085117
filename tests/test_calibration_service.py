"""The calibration's shells: saved models, ``balloon calibrate``, POST /v1/calibrate,
GET /v1/effects, and a saved model answering /v1/predict."""

from __future__ import annotations

import json

import numpy as np
import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for

import service.cli
from service.app import create_app
from solver.design import Design
from solver.errors import InputError
from surrogate.calibration import (
    EFFECT_IDS,
    ModelNotFoundError,
    load_model,
    run_calibration,
    save_model,
)


def measured_rows(offset_deg: float = 0.0, seed: int = 3) -> list[dict]:
    """Shell-test data: the paper's model itself (the baseline these tests save and
    reload) at three designs, 3 specimens (2 % scatter), 0.3 deg noise, plus an angle
    offset. The calibration's quality is tested on FE data in test_calibration_loop."""
    from surrogate import paper_surrogate

    rng = np.random.default_rng(seed)
    model = paper_surrogate()
    rows = []
    for L in (4.1, 7.1, 11.1):
        p = np.linspace(0.0, 1600.0, 10)
        for s in range(3):
            a = model.predict(Design(L_mm=L, t_mm=0.5), p).angle_deg
            a = a * (1 + 0.02 * rng.standard_normal()) + offset_deg
            a = a + 0.3 * rng.standard_normal(p.size)
            rows += [{"curve_id": f"L{L}-s{s}", "L_mm": L, "t_mm": 0.5,
                      "body_material": "pdms_1_10", "membrane_material": "ecoflex_00_30",
                      "pressure_pa": float(pi), "angle_deg": round(float(ai), 3),
                      "time_s": float(i), "flow_ul_s": 2.5}
                     for i, (pi, ai) in enumerate(zip(p, a, strict=True))]
    return rows


def main(argv: list[str]) -> int:
    """``balloon`` with only this command registered (others may not import yet)."""
    saved = service.cli.COMMAND_MODULES
    service.cli.COMMAND_MODULES = ("service.commands.calibrate",)
    try:
        return service.cli.main(argv)
    finally:
        service.cli.COMMAND_MODULES = saved


@pytest.fixture(scope="module")
def offset_calibration():
    """2 deg angle offset: selected and saved below."""
    return run_calibration(measured_rows(2.0), "paper")


def test_saved_model_predicts_with_the_effect(tmp_path, offset_calibration):
    path = save_model(offset_calibration, "lab1", tmp_path)
    assert path.exists()
    model = load_model("lab1", tmp_path)
    assert model.provenance["data_sha256"] == offset_calibration.obs.sha256
    assert model.provenance["selected_effects"] == ["angle_offset"]
    p = model.predict(Design(), np.array([0.0, 1000.0]), level=0.95)
    assert p.angle_deg[0] == pytest.approx(2.0, abs=0.4)  # the offset at zero pressure
    assert np.all(p.upper_deg > p.angle_deg) and p.validity["in_domain"]
    with pytest.raises(InputError):  # nothing stored is replaced silently
        save_model(offset_calibration, "lab1", tmp_path)
    with pytest.raises(ModelNotFoundError):
        load_model("nope", tmp_path)
    with pytest.raises(InputError):
        save_model(offset_calibration, "../evil", tmp_path)


def test_cli_writes_report_plot_and_model(tmp_path, capsys):
    rows = measured_rows(2.0)
    cols = list(rows[0])
    data = tmp_path / "data.csv"
    data.write_text("\n".join([",".join(cols)] + [",".join(str(r[c]) for c in cols)
                                                  for r in rows]))
    code = main(["calibrate", str(data), "--report", str(tmp_path / "r.json"), "--plot",
                 str(tmp_path / "r.png"), "--save", "m1", "--model", "paper",
                 "--models-dir", str(tmp_path / "models")])
    assert code == 0
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["selected_effects"] == ["angle_offset"]
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "models" / "m1.json").exists()


def test_cli_bad_file_is_one_line_exit_2(tmp_path, capsys):
    data = tmp_path / "bad.csv"
    data.write_text("curve_id,L_mm,t_mm,body_material,membrane_material,pressure_pa\n")
    code = main(["calibrate", str(data), "--report", str(tmp_path / "r.json"),
                 "--model", "paper"])
    assert code == 2
    err = capsys.readouterr().err
    assert "angle_deg" in err and err.count("\n") == 1
    assert not (tmp_path / "r.json").exists()


@pytest.fixture()
def client(tmp_path):
    app = create_app(settings_for(tmp_path, max_body_bytes=1_000_000), load_surrogate=False)
    with TestClient(app) as c:
        yield c


def test_effects_lists_the_catalogue(client):
    r = client.get("/v1/effects")
    assert r.status_code == 200
    items = r.json()["items"]
    assert [e["id"] for e in items] == list(EFFECT_IDS)
    hydraulic = next(e for e in items if e["id"] == "hydraulic_resistance")
    assert hydraulic["parameters"][0]["unit"] == "Pa per ul/s"
    assert "flow_ul_s" in hydraulic["needs"]


def test_calibrate_endpoint_and_saved_model_in_predict(client):
    rows = measured_rows(2.0)
    r = client.post("/v1/calibrate", json={"rows": rows, "model": "paper"})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["selected_effects"] == ["angle_offset"]
    assert body["rmse_after_deg"] < body["rmse_before_deg"]
    r = client.post("/v1/calibrate", json={"rows": rows, "model": "paper", "save": "lab2"})
    assert_problem(r, 401)
    r = client.post("/v1/calibrate", json={"rows": rows, "model": "paper", "save": "lab2"},
                    headers={"X-API-Key": "test-key"})
    assert r.status_code == 200 and r.json()["saved_model"] == "lab2"
    r = client.post("/v1/predict", json={"design": {"L_mm": 7.1, "t_mm": 0.5},
                                         "pressures_pa": [0, 500], "model": "lab2"})
    assert r.status_code == 200, r.text
    assert r.json()["angle_deg"][0] == pytest.approx(2.0, abs=0.4)


def test_calibrate_endpoint_names_row_and_column(client):
    rows = measured_rows()
    rows[5]["t_mm"] = -1
    r = client.post("/v1/calibrate", json={"rows": rows, "model": "paper"})
    body = assert_problem(r, 422)
    assert body["errors"][0]["field"] == "rows.5.t_mm"
    assert "row 6" in body["detail"]



def test_a_models_directory_that_is_a_file_is_said_not_a_name_conflict(tmp_path):
    """Every save answered 409 "a model named ... already exists" and /v1/health said ok
    (an audit of the thirty-fifth session)."""
    models = tmp_path / "models"
    models.write_text("not a directory")
    app = create_app(settings_for(tmp_path, models_dir=models), load_surrogate=False)
    with TestClient(app) as c:
        health = c.get("/v1/health").json()
        assert health["status"] == "degraded"
        assert any("BALLOON_MODELS_DIR" in p for p in health["problems"])
        from service.routes.calibration import EXAMPLE_ROWS

        r = c.post("/v1/calibrate", json={"rows": EXAMPLE_ROWS, "model": "paper",
                                          "save": "z1"}, headers={"X-API-Key": "test-key"})
    problem = assert_problem(r, 503)
    assert "BALLOON_MODELS_DIR" in problem["detail"] and str(tmp_path) not in r.text


@pytest.mark.parametrize("model", ["../x", "a/b", "emulator\x00"])
def test_a_model_name_that_is_a_path_is_refused_as_predict_refuses_it(model):
    from service.routes.calibration import EXAMPLE_ROWS

    with TestClient(create_app()) as c:
        r = c.post("/v1/calibrate", json={"rows": EXAMPLE_ROWS, "model": model})
    assert "not of this form" in assert_problem(r, 422, "model")["detail"]
