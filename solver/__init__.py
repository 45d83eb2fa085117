"""Finite-element solver for bending balloon actuators (3D, large deformation, Ogden).

Public surface::

    from solver import Design, SolverSettings, Curve, solve, MATERIALS
    curve = solve(Design(L_mm=7.1, t_mm=0.5), SolverSettings())
"""

from solver.curve import Curve
from solver.design import Design, design_from_dict, material_from_input
from solver.errors import BalloonError, ConvergenceError, InputError, NotFoundError, SolverError
from solver.materials import MATERIALS, OgdenMaterial, get_material, make_material
from solver.settings import SolverSettings, settings_from_dict

__all__ = [
    "MATERIALS", "BalloonError", "ConvergenceError", "Curve", "Design", "InputError",
    "NotFoundError", "OgdenMaterial", "SolverError", "SolverSettings", "design_from_dict",
    "get_material", "make_material", "material_from_input", "settings_from_dict", "solve",
]


def solve(design, settings=None, on_step=None):  # noqa: ANN001 - documented in solver.stepping
    """Solve one design; see ``solver.stepping.solve``. Imported lazily: the FE stack
    (scikit-fem) is only loaded by code that solves."""
    from solver.stepping import solve as _solve

    return _solve(design, settings, on_step=on_step)
