"""Saved calibrated models: of two concurrent saves of one name exactly one wins and the
other is told (409 over HTTP), a damaged or malformed model file is a clear answer naming
the model, and ``balloon predict --model NAME`` uses a saved model."""

from __future__ import annotations

import json
import threading
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for
from test_calibration_service import measured_rows as _shell_rows

import surrogate.calibration._saved as saved
from service.app import create_app
from surrogate.calibration import load_model, run_calibration, save_model
from surrogate.calibration._saved import ModelExistsError
from surrogate.file_seal import KEY


def measured_rows(effect: dict | None = None, reps: int = 3) -> list[dict]:
    """Shell-test rows (test_calibration_service): an angle offset, ``reps`` specimens
    per design; these tests check saving and loading, not the calibration's science."""
    rows = _shell_rows((effect or {}).get("offset", 0.0))
    keep = {f"-s{s}" for s in range(reps)}
    return [r for r in rows if any(r["curve_id"].endswith(k) for k in keep)]


@pytest.fixture(scope="module")
def calibration():
    return run_calibration(measured_rows({"offset": 2.0}), "paper")


def test_a_save_racing_another_of_the_same_name_loses(tmp_path, calibration, monkeypatch):
    """Deterministic race: the second save runs to completion while the first is between
    its existence check and its write. Check-then-replace lets both 'succeed' (the
    first silently replacing the second); an atomic create lets exactly one win."""
    real_dumps = json.dumps
    outcome = {}

    def dumps_then_race(*args, **kwargs):
        monkeypatch.setattr(saved.json, "dumps", real_dumps)
        try:
            outcome["second"] = save_model(calibration, "lab1", tmp_path)
        except ModelExistsError as exc:
            outcome["second"] = exc
        return real_dumps(*args, **kwargs)

    monkeypatch.setattr(saved.json, "dumps", dumps_then_race)
    with pytest.raises(ModelExistsError, match="'lab1' already exists"):
        save_model(calibration, "lab1", tmp_path)
    assert outcome["second"] == tmp_path / "lab1.json"  # the one that won
    assert load_model("lab1", tmp_path).name == "lab1"
    assert [p.name for p in tmp_path.iterdir()] == ["lab1.json"]  # no temporary left


def test_concurrent_saves_in_threads_exactly_one_wins(tmp_path, calibration):
    results: list[object] = []
    barrier = threading.Barrier(8)

    def save():
        barrier.wait()
        try:
            results.append(save_model(calibration, "race", tmp_path))
        except ModelExistsError as exc:
            results.append(exc)

    threads = [threading.Thread(target=save) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wins = [r for r in results if not isinstance(r, Exception)]
    assert len(wins) == 1 and len(results) == 8
    assert load_model("race", tmp_path).name == "race"


@pytest.fixture
def client(tmp_path):
    app = create_app(settings_for(tmp_path), load_surrogate=False)
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


def test_a_second_save_over_http_is_409_naming_the_name(client, calibration):
    save_model(calibration, "lab1", client.app.state.settings.models_dir)
    rows = measured_rows({"offset": 2.0})
    r = client.post("/v1/calibrate", headers={"X-API-Key": "test-key"},
                    json={"rows": rows, "model": "paper", "save": "lab1"})
    body = assert_problem(r, 409)
    assert "'lab1' already exists" in body["detail"] and body["model"] == "lab1"
    assert str(client.app.state.settings.models_dir) not in r.text  # no local path


def _good_doc(calibration, tmp_path):
    """A saved model's content as an earlier version wrote it (no checksum): its
    structure is what is checked (a sealed file's damage is refused by its checksum
    first, tests/test_saved_model_seal.py)."""
    save_model(calibration, "good", tmp_path / "src")
    doc = json.loads((tmp_path / "src" / "good.json").read_text())
    doc.pop(KEY, None)
    return doc


def _damage(doc, how):
    doc = json.loads(json.dumps(doc))
    if how == "no families":
        del doc["families"]
    elif how == "family lacks a_t_pa":
        del doc["families"][0]["a_t_pa"]
    elif how == "text for a number":
        doc["families"][0]["T_mm"] = "1.0"
    elif how == "effects not numbers":
        doc["effects"] = {"offset_deg": [1]}
    elif how == "domain not a pair":
        doc["domain"]["L_mm"] = 7.1
    elif how == "newer version":
        doc["format"] = "balloon.calibrated-model/9"
    elif how == "rmse text":
        doc["rmse_deg"] = "small"
    return doc


DAMAGES = ["no families", "family lacks a_t_pa", "text for a number", "effects not numbers",
           "domain not a pair", "newer version", "rmse text"]


@pytest.mark.parametrize("how", DAMAGES)
def test_a_malformed_saved_model_is_503_naming_the_model(client, calibration, tmp_path, how):
    models_dir = client.app.state.settings.models_dir
    models_dir.mkdir(parents=True, exist_ok=True)
    (models_dir / "broken.json").write_text(json.dumps(_damage(_good_doc(calibration,
                                                                         tmp_path), how)))
    r = client.post("/v1/predict", json={"pressures_pa": [0, 500], "model": "broken"})
    body = assert_problem(r, 503)
    assert "'broken'" in body["detail"] and str(models_dir) not in r.text


@pytest.mark.parametrize("content", [b"\xff\xfe{", b"{not json", b"[1, 2]", b"[" * 100_000])
def test_an_undecodable_saved_model_is_503(client, content):
    models_dir = client.app.state.settings.models_dir
    models_dir.mkdir(parents=True, exist_ok=True)
    (models_dir / "broken.json").write_bytes(content)
    r = client.post("/v1/predict", json={"pressures_pa": [0], "model": "broken"})
    assert "'broken'" in assert_problem(r, 503)["detail"]


def test_an_unknown_model_is_404_without_the_other_models_or_the_directory(client,
                                                                         calibration):
    models_dir = client.app.state.settings.models_dir
    save_model(calibration, "someone-elses-model", models_dir)
    r = client.post("/v1/predict", json={"pressures_pa": [0], "model": "nope"})
    body = assert_problem(r, 404)
    assert "'nope'" in body["detail"]
    assert "someone-elses-model" not in r.text and str(models_dir) not in r.text


def balloon(argv):
    from service.cli import main

    return main(argv)


def test_balloon_predict_uses_a_saved_model_by_name(tmp_path, calibration, capsys):
    save_model(calibration, "lab1", tmp_path)
    code = balloon(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "0", "500",
                    "--model", "lab1", "--models-dir", str(tmp_path), "--json"])
    out = capsys.readouterr().out
    assert code == 0, out
    pred = json.loads(out)
    expected = load_model("lab1", tmp_path).predict(
        __import__("solver.design", fromlist=["Design"]).Design(), [0.0, 500.0])
    assert pred["angle_deg"] == pytest.approx(expected.angle_deg.tolist())
    assert pred["angle_deg"][0] == pytest.approx(2.0, abs=0.4)  # the calibrated offset
    code = balloon(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "500",
                    "--model", "lab1", "--models-dir", str(tmp_path),
                    "--body-material", "pdms_1_10"])
    out = capsys.readouterr().out
    assert code == 0 and out.startswith("model lab1 (calibrated)"), out


def test_balloon_predict_with_an_unknown_or_damaged_saved_model_is_one_line(tmp_path,
                                                                           capsys):
    code = balloon(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "500",
                    "--model", "nope", "--models-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "'nope'" in err
    (tmp_path / "broken.json").write_text('{"format": "balloon.calibrated-model/1"}')
    code = balloon(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "500",
                    "--model", "broken", "--models-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and "'broken'" in err, err


def test_balloon_inverse_with_a_saved_model_is_one_line(tmp_path, calibration, capsys):
    save_model(calibration, "lab1", tmp_path)
    code = balloon(["inverse", "--L-mm", "7.1", "--t-mm", "0.5", "--angles-deg", "30",
                    "--model", "lab1", "--models-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "does not invert" in err, err


def test_balloon_calibrate_on_thin_data_without_replicates_finishes(tmp_path, capsys):
    """One short curve per design: no noise floor (null in the report); the summary line
    says so instead of crashing after the model was saved."""
    rows = [r for r in measured_rows({"offset": 2.0}, reps=1) if r["time_s"] % 2 == 0]
    cols = list(rows[0])
    data = tmp_path / "thin.csv"
    data.write_text("\n".join([",".join(cols)] + [",".join(str(r[c]) for c in cols)
                                                  for r in rows]))
    code = balloon(["calibrate", str(data), "--report", str(tmp_path / "r.json"),
                    "--model", "paper", "--save", "thin", "--models-dir",
                    str(tmp_path / "models")])
    out = capsys.readouterr().out
    assert code == 0
    assert json.loads((tmp_path / "r.json").read_text())["noise_floor_deg"] is None
    assert "noise floor n/a" in out
    assert load_model("thin", tmp_path / "models").name == "thin"


def test_balloon_calibrate_refuses_a_taken_name_before_the_work(tmp_path, calibration,
                                                                capsys):
    save_model(calibration, "lab1", tmp_path / "models")
    data = Path(__file__).resolve().parents[1] / "surrogate/calibration/data/example_lab.csv"
    code = balloon(["calibrate", str(data), "--report",
                    str(tmp_path / "r.json"), "--model", "paper", "--save", "lab1",
                    "--models-dir", str(tmp_path / "models")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "'lab1' already exists" in err, err
    assert not (tmp_path / "r.json").exists()  # nothing was run
