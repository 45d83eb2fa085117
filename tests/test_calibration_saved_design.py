"""A calibration against the emulator, saved and answered (surrogate/calibration/
_saved_design.py): the lab's actuators as the emulator at the design changed by the
selected physical effects. The lab data are FE curves of the shipped database with a
softer membrane than the preset (the unseen set membrane-0.61-L15.8: the record read
through the exact stiffness invariance), not the fitting code's forms."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from service_fakes import settings_for
from test_calibration_unseen import _emulator, calibrated

from solver import Design
from solver.materials import get_material
from surrogate.calibration import (
    load_model,
    observations_from_rows,
    run_calibration,
    save_model,
)
from surrogate.calibration._saved import SavedModelError
from surrogate.file_seal import KEY


@pytest.fixture(scope="module")
def membrane_case():
    # the unseen case's own calibration (one per process: calibrated)
    cal, error, rows = calibrated("membrane-0.61-L15.8", 0, _emulator)
    assert error is None and cal.report["selected_effects"] == ["membrane_stiffness"]
    return rows, cal


def test_a_calibration_against_the_emulator_is_saved_and_predicts_the_lab_data(
        membrane_case, tmp_path):
    """Saved, it answers for the lab's actuators: the measured angles (by the pump's
    volume, no gauge or camera effect in these data) within the calibration's own
    cross-validated error, where the emulator as is misses them by 3x that."""
    rows, cal = membrane_case
    save_model(cal, "lab1", tmp_path)
    doc = json.loads((tmp_path / "lab1.json").read_text())
    assert doc["format"] == "balloon.calibrated-design-model/1"
    assert set(doc["applied"]) == {"membrane_stiffness"} and doc["recorded"] == {}
    model = load_model("lab1", tmp_path, design_space=_emulator)
    emulator = _emulator()
    obs = observations_from_rows(rows)           # each reading's injected volume
    d, first = obs.design(0), obs.curve == 0
    v, angles = obs.volume_ul[first], obs.angle_deg[first]
    ours = model.predict_volume(d, v).angle_deg
    as_is = emulator.predict_volume(d, v).angle_deg
    ok = np.isfinite(ours) & np.isfinite(as_is)
    assert ok.sum() >= 5
    rms_ours = float(np.sqrt(np.mean((ours[ok] - angles[ok]) ** 2)))
    rms_as_is = float(np.sqrt(np.mean((as_is[ok] - angles[ok]) ** 2)))
    assert rms_ours < 1.5 * cal.report["rmse_after_deg"] + 0.5
    assert rms_as_is > 2.0 * rms_ours, (rms_ours, rms_as_is)   # 0.8 against 6.0 deg
    # by pressure it is the emulator at the softer membrane, its band at least the
    # emulator's there (widened by the scale's own sd)
    s = cal.report["fitted"]["effects"]["membrane_mu_scale"]["value"]
    softer = model.changed(d)
    assert softer.membrane_material.mu_kpa[0] == pytest.approx(
        s * d.membrane_material.mu_kpa[0])
    p = np.linspace(100.0, 3000.0, 12)
    a, b = model.predict(d, p), emulator.predict(softer, p)
    np.testing.assert_allclose(a.angle_deg, b.angle_deg)
    fin = np.isfinite(b.angle_deg)
    assert np.all(a.lower_deg[fin] <= b.lower_deg[fin] + 1e-12)
    assert np.all(a.upper_deg[fin] >= b.upper_deg[fin] - 1e-12)
    assert np.any(a.upper_deg[fin] - a.lower_deg[fin] > b.upper_deg[fin] - b.lower_deg[fin])
    assert a.model == "lab1" and a.design == d
    assert any("membrane_mu_scale x 0.6" in m for m in a.validity["messages"])
    # and it inverts: the pressure for angles it predicts
    inv = model.inverse(d, a.angle_deg[fin][2:5])
    np.testing.assert_allclose(inv.pressure_pa, p[fin][2:5], rtol=2e-3)
    # its volume band carries the scale's sd too (a pump user's "how much fluid": it had
    # kept the emulator's, 20-35x narrower than the forward answer implied)
    plain = emulator.inverse(softer, a.angle_deg[fin][2:5])
    assert np.all(inv.volume_upper_ul - inv.volume_lower_ul
                  > plain.volume_upper_ul - plain.volume_lower_ul)
    assert np.all(inv.upper_pa - inv.lower_pa > plain.upper_pa - plain.lower_pa)


def test_the_saved_design_model_refuses_other_pairs_and_damaged_files(membrane_case,
                                                                      tmp_path):
    _, cal = membrane_case
    save_model(cal, "lab2", tmp_path)
    model = load_model("lab2", tmp_path, design_space=_emulator)
    with pytest.raises(Exception, match="calibrated pairs") as err:
        model.predict(Design(body_material=get_material("ecoflex_00_30"),
                             membrane_material=get_material("pdms_1_15")), [500.0])
    assert getattr(err.value, "field", None) == "body_material"
    text = (tmp_path / "lab2.json").read_text()
    doc = json.loads(text)
    assert isinstance(doc.pop(KEY), str)     # sealed as the emulator's file is
    doc["applied"]["membrane_stiffness"]["membrane_mu_scale"]["value"] = "soft"
    (tmp_path / "lab3.json").write_text(json.dumps(doc))  # as an earlier version wrote it
    with pytest.raises(SavedModelError, match="membrane_mu_scale"):
        load_model("lab3", tmp_path, design_space=_emulator)
    # the sealed file with its scale 0.61 raised to 0.71 (still a scale a fit gives)
    assert text.count('"value": 0.6') == 1
    (tmp_path / "lab3.json").write_text(text.replace('"value": 0.6', '"value": 0.7'))
    with pytest.raises(SavedModelError, match="'lab3'.*checksum does not match"):
        load_model("lab3", tmp_path, design_space=_emulator)
    with pytest.raises(SavedModelError, match="not loaded"):
        load_model("lab2", tmp_path)


def test_saved_over_http_it_answers_predict_by_volume_and_the_inverse(membrane_case,
                                                                      tmp_path):
    """POST /v1/calibrate with save against the emulator (refused until 2026-12-06), then
    the saved name in /v1/predict (pressure and volume) and /v1/inverse/pressure."""
    rows, _ = membrane_case
    from service.app import create_app

    app = create_app(settings_for(tmp_path), load_surrogate=False)
    app.state.models.emulator = _emulator()
    with TestClient(app) as client:
        r = client.post("/v1/calibrate", json={"rows": rows, "model": "emulator",
                                               "save": "lab4"},
                        headers={"X-API-Key": "test-key"})
        assert r.status_code == 200, r.text
        assert r.json()["saved_model"] == "lab4"
        design = {k: rows[0][k] for k in ("L_mm", "t_mm", "body_material",
                                          "membrane_material")}
        by_p = client.post("/v1/predict", json={"design": design, "model": "lab4",
                                                "pressures_pa": [500, 1500]})
        assert by_p.status_code == 200, by_p.text
        by_v = client.post("/v1/predict", json={"design": design, "model": "lab4",
                                                "volumes_ul": [5, 20]})
        assert by_v.status_code == 200, by_v.text
        inv = client.post("/v1/inverse/pressure", json={"design": design, "model": "lab4",
                                                        "angles_deg": [20.0]})
        assert inv.status_code == 200, inv.text
        assert inv.json()["pressure_pa"][0] > 0
        search = client.post("/v1/inverse", json={"model": "lab4", "target": {
            "pressure_pa": 1500, "angle_deg": 30}})
        assert search.status_code == 422 and "design search" in search.json()["detail"]


DATA = Path(__file__).resolve().parent / "data" / "lab_t055_labelled_t05.csv"


def test_a_thicker_membrane_at_the_box_face_is_fitted_and_an_unexplained_rest_not_saved(
        tmp_path):
    """A 0.05 mm thicker membrane than the nominal 0.5 mm (the box's face: dt >= 0) was
    fitted as dt = 2e-10 from a start on the bound; it is found now. The emulator's
    misfit of this solve still leaves a shared residual the catalogue does not explain, so
    the calibration is not saved: saved, it had answered 81 deg [78, 84] at 2000 Pa where
    the FE gives 61 (an audit of 2026-12-06)."""
    from solver.errors import InputError
    from surrogate.calibration import load_observations

    cal = run_calibration(load_observations(DATA), _emulator())
    thickness = next(c for c in cal.report["candidates"] if c["effect"] == "membrane_thickness")
    assert abs(thickness["params"]["dt_mm"]["value"] - 0.05) < 0.015
    assert cal.report["residual_structured_after"]
    with pytest.raises(InputError, match="leaves structure") as err:
        save_model(cal, "labA", tmp_path)
    assert err.value.field == "save" and not list(tmp_path.iterdir())


def test_an_exponential_baseline_without_a_cross_validated_error_says_so_and_is_not_saved(
        tmp_path):
    """With the exponential model the held-out curves reach past its range: the report
    said "predicts unseen curves to inf deg ... consistent with replicate scatter", and a
    save was a 500 (a NaN in the file)."""
    from service.settings import DATA_DIR
    from solver.errors import InputError
    from surrogate import load_surrogate
    from surrogate.calibration import load_observations

    cal = run_calibration(load_observations(DATA), load_surrogate(DATA_DIR / "surrogate.json"))
    text = cal.report["interpretation"]
    assert "inf" not in text and "no error to report" in text
    with pytest.raises(InputError, match="no cross-validated error") as err:
        save_model(cal, "expA", tmp_path)
    assert err.value.field == "save"


def test_a_saved_model_flags_every_design_input_it_was_not_calibrated_at_and_no_search(
        membrane_case, tmp_path, monkeypatch, capsys):
    """Only L and t were checked: another T, b, h or W was carried over without a flag;
    and the CLI ran a design search with a saved model that HTTP refuses (an audit of
    2026-12-06)."""
    from service import cli
    from service.commands import inverse as inverse_command

    rows, cal = membrane_case
    save_model(cal, "lab5", tmp_path)
    model = load_model("lab5", tmp_path, design_space=_emulator)
    d = observations_from_rows(rows).design(0)
    flags = model.predict(replace(d, T_mm=2.0), [300.0]).validity["flags"]
    assert "T_mm_outside_calibration" in flags and "L_mm_outside_calibration" not in flags
    assert model.predict(d, [300.0]).validity["flags"] == []
    # a membrane scaled in the request: the lab's scale multiplies it, and it is said
    from solver.design_space import scaled_material

    scaled = replace(d, membrane_material=scaled_material(d.membrane_material.id, 1.2))
    said = model.predict(scaled, [300.0]).validity["messages"]
    assert any("scaled already" in m and "multiplies it" in m for m in said)
    monkeypatch.setattr(inverse_command, "surrogate_from_args", lambda args: model)
    assert cli.main(["inverse", "--angle-deg", "30", "--pressure-pa", "1500",
                     "--model", "lab5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--model" in err and "design search" in err
