"""Saved calibrated models are sealed as the emulator and exponential files are
(surrogate/file_seal.py, ``content_sha256``): a file changed after saving -- one digit of
a parameter raised, as the audit did (a_deg_per_mm 0.203 -> 0.293 had answered 8.27 deg
for 5.74 with no flag) -- is refused on load, a 503 problem naming the model over HTTP
and one line in the CLI, never answered with other numbers. A file of earlier versions
carries no checksum: it still answers, every answer flagged ``saved_without_checksum``
with how to have it checked (surrogate/calibration/_saved.py)."""

from __future__ import annotations

import json
import re

import pytest
from fastapi.testclient import TestClient
from service_fakes import assert_problem, settings_for
from test_service_saved_models import measured_rows

from service.app import create_app
from service.cli import main
from solver import Design
from surrogate import paper_surrogate
from surrogate.calibration import load_model, run_calibration, save_model
from surrogate.calibration._saved import SavedModelError
from surrogate.calibration._saved_design import DESIGN_FORMAT
from surrogate.file_seal import KEY, seal

FLAG = "saved_without_checksum"
PREDICT = {"design": {"L_mm": 7.1, "t_mm": 0.5}, "pressures_pa": [0, 500], "model": "lab1"}


@pytest.fixture(scope="module")
def calibration():
    return run_calibration(measured_rows({"offset": 2.0}), "paper")


def raise_a_digit(text: str) -> str:
    """``text`` with a_deg_per_mm's second decimal digit raised (0.203 -> 0.293): the
    file still parses and passes every structural check."""
    m = re.search(r'"a_deg_per_mm": \d+\.\d(\d)', text)
    assert m, text
    digit = "9" if m.group(1) != "9" else "1"
    return text[:m.start(1)] + digit + text[m.end(1):]


def unsealed(text: str) -> str:
    """The file as an earlier version wrote it: the same content without a checksum."""
    doc = json.loads(text)
    del doc[KEY]
    return json.dumps(doc, indent=1)


def test_a_saved_model_is_sealed_and_a_raised_digit_is_refused_naming_the_model(
        calibration, tmp_path):
    path = save_model(calibration, "lab1", tmp_path)
    text = path.read_text()
    assert json.loads(text)[KEY] == seal({k: v for k, v in json.loads(text).items()
                                          if k != KEY})[KEY]
    assert text.startswith("{\n")           # still indented: a lab reads its model
    model = load_model("lab1", tmp_path)
    assert FLAG not in model.predict(Design(), [500.0]).validity["flags"]
    path.write_text(raise_a_digit(text))
    with pytest.raises(SavedModelError, match=r"'lab1'.*content_sha256 checksum does not "
                       "match") as err:
        load_model("lab1", tmp_path)
    assert str(tmp_path) not in str(err.value)


def test_an_edited_saved_model_is_503_over_http_and_one_line_in_the_cli(calibration,
                                                                         tmp_path, capsys):
    app = create_app(settings_for(tmp_path), load_surrogate=False)
    models_dir = app.state.settings.models_dir
    path = save_model(calibration, "lab1", models_dir)
    path.write_text(raise_a_digit(path.read_text()))
    with TestClient(app, raise_server_exceptions=False) as client:
        r = client.post("/v1/predict", json=PREDICT)
    body = assert_problem(r, 503)
    assert "'lab1'" in body["detail"] and "checksum" in body["detail"], body
    assert str(tmp_path) not in r.text and "Traceback" not in r.text
    code = main(["predict", "--L-mm", "7.1", "--t-mm", "0.5", "--pressures", "500",
                 "--model", "lab1", "--models-dir", str(models_dir)])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1, err
    assert "'lab1'" in err and "checksum" in err and "Traceback" not in err


def test_a_model_saved_without_a_checksum_still_answers_flagged(calibration, tmp_path):
    """A lab's model of last month: the same numbers as before, and every answer says the
    file is unchecked and how to re-save it; ``in_domain`` is about the design, unchanged."""
    sealed = save_model(calibration, "lab1", tmp_path / "now")
    old = tmp_path / "models" / "lab1.json"
    old.parent.mkdir()
    old.write_text(unsealed(sealed.read_text()))
    p = [0.0, 500.0, 1000.0]
    now = load_model("lab1", tmp_path / "now").predict(Design(), p)
    before = load_model("lab1", tmp_path / "models").predict(Design(), p)
    assert before.angle_deg.tolist() == now.angle_deg.tolist()
    assert before.validity["flags"] == now.validity["flags"] + [FLAG]
    note = before.validity["messages"][-1]
    assert "'lab1' carries no checksum" in note and "save it under a new name" in note
    assert before.validity["in_domain"] == now.validity["in_domain"]
    app = create_app(settings_for(tmp_path), load_surrogate=False)
    with TestClient(app) as client:
        r = client.post("/v1/predict", json=PREDICT)
    assert r.status_code == 200, r.text
    validity = r.json()["validity"]
    assert FLAG in validity["flags"] and note in validity["messages"]
    assert validity["in_domain"] is True


def design_doc() -> dict:
    """A calibration against a design-space model (no physical effect selected), as a
    file holds it; answered here through the paper's model for speed."""
    return {"format": DESIGN_FORMAT, "name": "lab5", "baseline": "emulator",
            "pairs": [["pdms_1_10", "ecoflex_00_30"]], "applied": {}, "recorded": {},
            "rmse_deg": 0.8, "domain": {"L_mm": [4.0, 18.0], "t_mm": [0.5, 1.2],
                                        "pressure_pa": [0.0, 5000.0]},
            "provenance": {"data_sha256": "0" * 64}}


def test_a_design_space_model_is_checked_by_its_seal_or_flagged_without_one(tmp_path):
    paper = paper_surrogate()
    path = tmp_path / "lab5.json"
    path.write_text(json.dumps(seal(design_doc()), indent=1))
    model = load_model("lab5", tmp_path, design_space=lambda: paper)
    assert FLAG not in model.predict(Design(), [500.0]).validity["flags"]
    path.write_text(path.read_text().replace('"rmse_deg": 0.8', '"rmse_deg": 0.3'))
    with pytest.raises(SavedModelError, match="'lab5'.*checksum"):
        load_model("lab5", tmp_path, design_space=lambda: paper)
    path.write_text(json.dumps(design_doc(), indent=1))       # an earlier version's file
    model = load_model("lab5", tmp_path, design_space=lambda: paper)
    for answer in (model.predict(Design(), [500.0]),
                   model.inverse(Design(), [20.0])):
        assert FLAG in answer.validity["flags"]
        assert any("'lab5' carries no checksum" in m for m in answer.validity["messages"])


@pytest.mark.parametrize("stored", [None, 12, "0" * 64])
def test_a_checksum_member_that_is_not_the_files_own_is_refused(calibration, tmp_path,
                                                               stored):
    """A seal set to null, a number or another digest is damage, not an older file."""
    path = save_model(calibration, "lab1", tmp_path)
    doc = json.loads(path.read_text())
    doc[KEY] = stored
    path.write_text(json.dumps(doc, indent=1))
    with pytest.raises(SavedModelError, match="'lab1'.*checksum"):
        load_model("lab1", tmp_path)
