"""Requests the service should not take on whole: a solve job whose FE model would not fit
the server's memory (one request with mesh level 2 of a 60 mm chamber took 17.8 GB before
its first step), a spring stiffness on a tip that has no spring (it keyed a second record
of the same solve), a body too short for its chamber (the refusal named the chamber
offset, with an empty range), and a layer stiffness ratio outside the box (the refusal
named the body when the membrane was off)."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient
from service_fakes import fast_solve, settings_for
from test_service_jobs import KEY

from service.app import create_app
from solver.design import Design
from solver.design_space import OutOfBoxError, locate
from solver.errors import InputError
from solver.mesh import estimated_dofs
from solver.settings import SolverSettings

BIG = {"L_mm": 60.0, "t_mm": 0.05, "body_length_mm": 100.0}


@pytest.fixture
def client(tmp_path):
    app = create_app(settings_for(tmp_path, db_path=tmp_path / "curves.h5"),
                     solve_fn=fast_solve, load_surrogate=False)
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


def test_the_dof_estimate_bounds_the_solvers_own_count():
    """``estimated_dofs`` counts the tensor grid's nodes (the chamber's and the clamp's
    too): an upper bound within a fifth of the model the solver builds."""
    from solver.discrete import ActuatorModel

    for design, settings in ((Design(), SolverSettings()),
                             (Design(L_mm=12.0, t_mm=1.1, b_mm=2.2), SolverSettings()),
                             (Design(), SolverSettings(element="hex1", mesh_level=1))):
        free = ActuatorModel(design.validated(), settings.validated()).n_free
        estimate = estimated_dofs(design, settings)
        assert free <= estimate <= 1.25 * free, (free, estimate)


def test_a_solve_too_big_for_the_server_is_refused_naming_the_mesh_level(client):
    body = {"design": BIG, "settings": {"mesh_level": 2}}
    r = client.post("/v1/solve", json=body, headers=KEY)
    assert r.status_code == 422 and r.headers["content-type"].startswith(
        "application/problem+json")
    problem = r.json()
    error = problem["errors"][0]
    assert error["field"] == "settings.mesh_level"
    assert "2,049,393 degrees of freedom" in problem["detail"]
    assert "BALLOON_MAX_SOLVE_DOFS" in problem["detail"]
    assert error["allowed"] == "0 <= mesh_level <= 0 for this design"
    # the level it allows is taken
    r = client.post("/v1/solve", json={"design": BIG, "settings": {"mesh_level": 0}},
                    headers=KEY)
    assert r.status_code == 202, r.text


def test_a_design_too_big_at_every_level_is_refused_naming_the_design(tmp_path):
    app = create_app(settings_for(tmp_path, db_path=tmp_path / "curves.h5",
                                  max_solve_dofs=5_000),
                     solve_fn=fast_solve, load_surrogate=False)
    with TestClient(app, raise_server_exceptions=False) as c:
        r = c.post("/v1/solve", json={"design": {"L_mm": 7.1}}, headers=KEY)
    assert r.status_code == 422
    assert r.json()["errors"][0]["field"] == "design"
    assert "11,661 degrees of freedom" in r.json()["detail"]


def test_a_spring_stiffness_on_a_tip_without_a_spring_is_refused(client):
    with pytest.raises(InputError, match="spring_k_n_per_m"):
        SolverSettings(tip="free", spring_k_n_per_m=5.0).validated()
    SolverSettings(tip="spring", spring_k_n_per_m=5.0).validated()
    r = client.post("/v1/solve", json={"design": {"L_mm": 9.1},
                                        "settings": {"tip": "free", "spring_k_n_per_m": 5}},
                    headers=KEY)
    assert r.status_code == 422
    assert r.json()["errors"][0]["field"] == "settings.spring_k_n_per_m"


def test_a_body_too_short_for_its_chamber_names_the_body_length():
    with pytest.raises(InputError) as caught:
        Design(L_mm=7.1, body_length_mm=5.0).validated()
    assert caught.value.field == "body_length_mm"
    assert caught.value.allowed == "body_length_mm >= L_mm + 0.2 = 7.3"
    assert Design(L_mm=7.1, body_length_mm=7.3).validated().chamber_offset_mm == \
        pytest.approx(0.1)


@pytest.mark.parametrize(("body", "membrane", "field"), [
    ("pdms_1_10", "ecoflex_00_30*10", "membrane_material"),
    ("pdms_1_10*0.1", "ecoflex_00_30", "body_material"),
    ("pdms_1_10*8", "ecoflex_00_30*0.5", "body_material")])
def test_a_stiffness_ratio_outside_the_box_names_the_layer_that_strays(body, membrane,
                                                                        field):
    with pytest.raises(OutOfBoxError) as caught:
        locate(Design(body_material=body, membrane_material=membrane), reduced=True)
    assert caught.value.field == field
    assert "s_body / s_membrane" in caught.value.detail
    assert caught.value.nearest is not None
    # both layers scaled by one factor: a scaled copy of a design in the box, answered
    assert locate(Design(body_material="pdms_1_10*100",
                         membrane_material="ecoflex_00_30*100"),
                  reduced=True).pressure_scale == pytest.approx(100.0)
