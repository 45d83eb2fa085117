"""One material id, one set of parameters: an inline material that reuses a preset id with
other parameters is refused by the service, and a fit over a database that holds such
records (written by other means) groups them by their physics, never by id alone."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from fastapi.testclient import TestClient
from service_fakes import FakeSurrogate, assert_problem, fast_solve, settings_for
from test_precompute_fakes import fake_curve

from service.app import create_app
from solver.design import Design
from solver.materials import MATERIALS, make_material
from solver.settings import SolverSettings
from solver.store import CurveStore, make_record
from surrogate import fit_surrogate
from surrogate.dataset import by_physics

SETTINGS = SolverSettings(mesh_level=0, element="hex1")
IMPOSTOR = {"id": "pdms_1_10", "mu_kpa": [60.0], "alpha": [3.0]}  # not Table 1's PDMS 1:10


@pytest.fixture
def client(tmp_path):
    app = create_app(settings_for(tmp_path), solve_fn=fast_solve,
                     write_fn=lambda d, s, c: "k" * 32, load_surrogate=False)
    app.state.models.fitted = FakeSurrogate()
    app.state.models.emulator = app.state.models.fitted
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


@pytest.mark.parametrize("path, extra", [("/v1/solve", {}),
                                         ("/v1/predict", {"pressures_pa": [500]})])
def test_an_inline_material_reusing_a_preset_id_is_refused(client, path, extra):
    body = {"design": {"L_mm": 7.1, "body_material": IMPOSTOR}, **extra}
    r = client.post(path, json=body, headers={"X-API-Key": "test-key"})
    problem = assert_problem(r, 422, "design.body_material.id")
    assert "reuses the preset id 'pdms_1_10'" in problem["detail"]


def test_an_inline_copy_of_a_preset_or_a_new_id_is_accepted(client):
    preset = MATERIALS["pdms_1_10"]
    same = {"id": "pdms_1_10", "mu_kpa": list(preset.mu_kpa), "alpha": list(preset.alpha)}
    for material in (same, {**IMPOSTOR, "id": "stiff_pdms"}):
        r = client.post("/v1/solve", headers={"X-API-Key": "test-key"},
                        json={"design": {"L_mm": 7.1, "body_material": material}})
        assert r.status_code == 202, r.text


def _scaled(design, scale):
    c = fake_curve(design)
    return dataclasses.replace(c, angle_deg=c.angle_deg * scale)


def test_the_fit_groups_records_by_physics_not_by_material_id(tmp_path):
    impostor = make_material(IMPOSTOR["id"], IMPOSTOR["mu_kpa"], IMPOSTOR["alpha"])
    grid = [(L, t) for L in (4.1, 7.1, 11.1) for t in (0.5, 0.75, 1.0)]
    genuine = [make_record(d, SETTINGS, _scaled(d, 1.0))
               for d in (Design(L_mm=L, t_mm=t) for L, t in grid)]
    stiffer = [make_record(d, SETTINGS, _scaled(d, 0.3))
               for d in (Design(L_mm=L, t_mm=t, body_material=impostor) for L, t in grid)]
    with CurveStore(tmp_path / "alone.h5", mode="a") as db:
        db.put_many(genuine)
    with CurveStore(tmp_path / "mixed.h5", mode="a") as db:
        db.put_many(genuine + stiffer)
    alone, mixed = fit_surrogate(tmp_path / "alone.h5"), fit_surrogate(tmp_path / "mixed.h5")
    top_pa = alone.family_for(Design()).domain.pressure_max_pa
    pressures = [0.25 * top_pa, 0.5 * top_pa]  # inside the FE's range: numbers
    assert np.isfinite(alone.predict(Design(), pressures).angle_deg).all()
    # the preset's family is fitted to the preset's records only
    assert mixed.predict(Design(), pressures).angle_deg.tolist() == pytest.approx(
        alone.predict(Design(), pressures).angle_deg.tolist(), rel=1e-9)
    assert len(mixed.family_fits) == 2


def test_by_physics_renames_only_what_is_ambiguous():
    soft_a, soft_b = make_material("soft", [1.0], [2.0]), make_material("soft", [2.0], [2.0])
    mine = make_material("mine", [1.0], [2.0])
    designs = [Design(), Design(membrane_material=soft_a), Design(membrane_material=soft_b),
               Design(membrane_material=mine),
               Design(body_material=make_material("pdms_1_10", [60.0], [3.0]))]
    names = [(d.body_material.id, d.membrane_material.id) for d in by_physics(designs)]
    assert names[0] == ("pdms_1_10", "ecoflex_00_30") and names[3][1] == "mine"
    assert names[1][1].startswith("soft~") and names[2][1].startswith("soft~")
    assert names[1][1] != names[2][1] and names[4][0].startswith("pdms_1_10~")


def test_a_design_takes_materials_by_preset_id_and_names_the_field_when_it_cannot():
    """A Python client writes Design(body_material="pdms_1_15"); before, the string went
    through and failed deep in the emulator with AttributeError ('str' has no 'alpha')."""
    from solver.errors import InputError

    d = Design(L_mm=9.0, body_material="pdms_1_15", membrane_material="ecoflex_00_30")
    assert d.body_material == MATERIALS["pdms_1_15"]
    assert d == Design(L_mm=9.0, body_material=MATERIALS["pdms_1_15"])
    for bad, words in (("pdms", "unknown material 'pdms'"), (3, "cannot read a material")):
        with pytest.raises(InputError) as info:
            Design(membrane_material=bad)
        assert info.value.field == "membrane_material" and words in str(info.value)


def test_a_scaled_preset_is_named_by_its_id_in_python_and_over_http(shipped_client):
    """``pdms_1_10*1.25`` (as the store and the design search name a preset with every mu
    scaled) is that material wherever a preset id is taken; a bad scale names the field."""
    from solver.design_space import scaled_material
    from solver.errors import InputError

    d = Design(body_material="ecoflex_00_30*1.5")
    assert d.body_material == scaled_material("ecoflex_00_30", 1.5)
    for bad in ("ecoflex_00_30*0", "ecoflex_00_30*x", "nosuch*1.5", "pdms_1_10*-2"):
        with pytest.raises(InputError) as info:
            Design(body_material=bad)
        assert info.value.field == "body_material" and "<preset>*<scale>" in str(info.value)
    by_id = shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 9.0, "body_material": "ecoflex_00_30*1.5",
                   "membrane_material": "ecoflex_00_30"}, "pressures_pa": [400, 800]})
    inline = shipped_client.post("/v1/predict", json={
        "design": {"L_mm": 9.0, "membrane_material": "ecoflex_00_30",
                   "body_material": scaled_material("ecoflex_00_30", 1.5).as_dict()},
        "pressures_pa": [400, 800]})
    assert by_id.status_code == inline.status_code == 200, by_id.text
    assert by_id.json()["angle_deg"] == inline.json()["angle_deg"]
    r = shipped_client.post("/v1/predict", json={"design": {"body_material": "pdms_1_10*zero"},
                                         "pressures_pa": [400]})
    assert_problem(r, 422)
    assert "body_material" in r.text
