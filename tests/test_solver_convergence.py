"""The balanced mesh (BALANCED_DIVISIONS, the candidate default) and the fine-x mesh
(FINE_X_DIVISIONS) are converged to the issue's targets; the shipped default (the former
level 0, on which the database and the emulator are built) is not, and the test says by
how much. A heavy FE case (marked slow, about 15
minutes on 2 quiet cores; run with ``pytest --runslow``).

Reference: the three members r = 1, 2, 3 of the x-and-layers family (solver/mesh.py:
r times the divisions along x and through the chamber and body layers of the former
level 0; the divisions across the width and through the membrane, converged to 0.2 Pa,
held), extrapolated with the observed order of each quantity (Richardson, three
levels). A candidate level 0 must read the angle at 1000-2000 Pa within 2 % and the
pressure at 30 and 60 deg within 1 % of it (docs/verification.md gives the measured
figures).
"""

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator

from solver import Design, SolverSettings
from solver.mesh import BALANCED_DIVISIONS, FINE_X_DIVISIONS, FORMER_DIVISIONS, xz_family
from solver.stepping import solve
from solver.verification.richardson import observed_order, richardson

ANGLES_DEG = [30.0, 60.0]
PRESSURES_PA = [1000.0, 1250.0, 1500.0, 1750.0, 2000.0]


def _pressure_at(curve, angles_deg):
    keep = curve.angle_deg > 2.0            # monotone above the transition regime
    return PchipInterpolator(curve.angle_deg[keep], curve.pressure_pa[keep])(angles_deg)


def _angle_at(curve, pressures_pa):
    keep = curve.pressure_pa > 300.0        # the angle is monotone in p above the transition
    return PchipInterpolator(curve.pressure_pa[keep], curve.angle_deg[keep])(pressures_pa)


def _extrapolated(values: np.ndarray) -> np.ndarray:
    h = np.array([1.0, 1 / 2, 1 / 3])
    out = []
    for f in values.T:
        q = observed_order(h, f)
        assert q is not None and 0.5 < q < 6.0, f"no observed order from {f}"
        out.append(richardson(h, f, q))
    return np.array(out)


@pytest.mark.slow
def test_candidate_meshes_are_within_the_targets_of_the_extrapolated_curve():
    settings = SolverSettings(max_angle_deg=65)
    assert settings.mesh_level == 0
    assert FORMER_DIVISIONS == xz_family(1)        # the former level 0
    candidates = [solve(Design(), settings, divisions=d)
                  for d in (BALANCED_DIVISIONS, FINE_X_DIVISIONS)]
    family = [solve(Design(), settings, divisions=xz_family(r)) for r in (1, 2, 3)]
    assert all(c.status == "complete" for c in candidates + family)
    p_ref = _extrapolated(np.array([_pressure_at(c, ANGLES_DEG) for c in family]))
    a_ref = _extrapolated(np.array([_angle_at(c, PRESSURES_PA) for c in family]))
    for c in candidates:
        p_err = _pressure_at(c, ANGLES_DEG) / p_ref - 1
        a_err = _angle_at(c, PRESSURES_PA) / a_ref - 1
        assert np.all(np.abs(p_err) < 0.01), p_err
        assert np.all(np.abs(a_err) < 0.02), a_err
    # the balanced mesh at about the default's dofs (1.03 x)
    assert candidates[0].n_dofs <= 1.05 * family[0].n_dofs
    # The former level 0 (r = 1) misses the angle target: the test can fail.
    a_old = _angle_at(family[0], PRESSURES_PA) / a_ref - 1
    assert np.any(np.abs(a_old) > 0.02)
