"""The default mesh is converged to the issue's 2 %: a heavy FE case (marked slow, about
5 minutes on 2 cores; run with ``pytest --runslow``).

Levels 0 and 1 are nested (level 1 halves every element size, solver/mesh.py); the
two-level Richardson estimate of the pressure at 30 and 60 deg with the pessimistic order
q = 1 bounds the mesh-converged value (docs/verification.md: the observed order of the
uniform coarse family is above 2). Measured: level 0 is +1.45 % / +0.79 % against it.
"""

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator

from solver import Design, SolverSettings
from solver.stepping import solve


def _pressure_at(curve, angles_deg):
    keep = curve.angle_deg > 2.0            # monotone above the transition regime
    return PchipInterpolator(curve.angle_deg[keep], curve.pressure_pa[keep])(angles_deg)


@pytest.mark.slow
def test_default_mesh_is_within_two_percent_of_the_extrapolated_curve():
    default = SolverSettings()
    assert default.mesh_level == 0
    p0 = _pressure_at(solve(Design(), SolverSettings(max_angle_deg=62)), [30, 60])
    p1 = _pressure_at(solve(Design(), SolverSettings(mesh_level=1, max_angle_deg=62)),
                      [30, 60])
    assert np.all(p1 < p0)                  # converging from the stiff side
    extrapolated_q1 = p1 - (p0 - p1)        # h1 = h0 / 2, order 1
    error = p0 / extrapolated_q1 - 1
    assert np.all(error < 0.02)
    assert np.all(error > 0)
