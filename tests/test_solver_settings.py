"""Solver settings from plain data (grid files, HTTP, saved records): every bad value is
refused with the field's name and the allowed range, never silently converted."""

import pytest

from solver import SolverSettings
from solver.errors import InputError
from solver.settings import MAX_MESH_LEVEL, settings_from_dict


@pytest.mark.parametrize("data, field, allowed", [
    ({"mesh_level": 0.5}, "mesh_level", "an integer"),
    ({"mesh_level": True}, "mesh_level", f"an integer 0 <= mesh_level <= {MAX_MESH_LEVEL}"),
    ({"max_angle_deg": False}, "max_angle_deg", "a number"),
    ({"mesh_level": MAX_MESH_LEVEL + 1}, "mesh_level", f"0 <= mesh_level <= {MAX_MESH_LEVEL}"),
    ({"newton_tol": 0.5}, "newton_tol", "newton_tol <= 0.01"),
    ({"element": "tet4"}, "element", "hex2 | hex1"),
    ({"mesh_divisions": "fine"}, "mesh_divisions", "former | balanced | fine_x"),
    ({"mesh_divisions": "default"}, "mesh_divisions", "former | balanced | fine_x"),
    ({"mesh_lvl": 1}, "mesh_lvl", "mesh_level"),
    ({"max_steps": "many"}, "max_steps", None),
])
def test_bad_values_name_the_field_and_the_range(data, field, allowed):
    with pytest.raises(InputError) as info:
        settings_from_dict(data)
    assert info.value.field == field
    if allowed is not None:
        assert allowed in str(info.value)


def test_whole_floats_and_defaults_are_read():
    s = settings_from_dict({"mesh_level": 1.0, "max_angle_deg": 45})
    assert s.mesh_level == 1 and isinstance(s.mesh_level, int)
    assert s.max_angle_deg == 45.0
    assert settings_from_dict({}) == SolverSettings()


def test_mesh_divisions_select_the_fine_x_mesh():
    # "fine_x" doubles every division along x (solver/mesh.py FINE_X_DIVISIONS) and
    # nothing else to the former level 0 ("former").
    from solver import Design
    from solver.discrete import ActuatorModel
    from solver.mesh import FINE_X_DIVISIONS, build_mesh

    default = ActuatorModel(Design(), SolverSettings(element="hex1", mesh_divisions="former"))
    fine = ActuatorModel(Design(), settings_from_dict({"element": "hex1",
                                                       "mesh_divisions": "fine_x"}))
    expected = build_mesh(Design(), 0, FINE_X_DIVISIONS).mesh
    assert fine.mesh.nelements == expected.nelements == 2 * default.mesh.nelements
