"""Two balloons sharing one pressure: the classic bifurcation under volume control.

Two identical thick-walled spheres (octant models, solver/verification/sphere.py) are
connected to one fluid cavity: the prescribed volume is their sum, the pressure is
shared. The second octant is the first turned by 180 degrees about the axis (1, -1, 0)
(x, y, z -> -y, -x, -z): it lies in the octant x, y, z <= 0, so both keep the symmetry
planes through the origin (u_i = 0 on X_i = 0, and x . n = 0 there, which the cavity
volume needs) and they share no node.

Physics (e.g. Mueller and Strehlow, Rubber and Rubber Balloons, 2004, ch. 2): with one
balloon's pressure p(v) rising to a maximum at v* and falling beyond, the state of two
equal balloons at total volume V = 2 v is stable at constant V while p'(v) > 0. At the
pressure maximum the volume-neutral mode "one grows, the other shrinks" (stiffness
proportional to p'(v)) goes through zero: a pitchfork bifurcation in V. Past it, the
tangent K has two negative eigenvalues (one per balloon), the bordered system one
(solver/stability.py): the symmetric branch is unstable under volume control, and the
stable branch has one balloon on the rising part of p(v) and one on the falling part.
For the neo-Hookean thin sphere, p ~ v^(-1/3) - v^(-7/3), p''' > 0 at the maximum, so
the pitchfork is supercritical: the unequal branch leaves the bifurcation with
|v1 - v2| growing like the square root of the excess volume.

``imperfection``: the second sphere's outer radius is (1 - imperfection) times the
first's (a slightly thinner wall), which turns the pitchfork into an imperfect one.
"""

from __future__ import annotations

import numpy as np
from skfem import MeshHex

from solver import cavity as cav
from solver.discrete import Evaluation, SolidModel
from solver.materials import OgdenMaterial
from solver.verification.sphere import (
    INNER_RADIUS_MM,
    OUTER_RADIUS_MM,
    _patch,
    shell_mesh,
    symmetry_mask,
)

TURN = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])   # det +1


def _octant(n: int, m: int, inner_mm: float, outer_mm: float) -> MeshHex:
    mesh = _patch(0, n, m, inner_mm, outer_mm)
    for axis in (1, 2):
        mesh = mesh + _patch(axis, n, m, inner_mm, outer_mm)
    return mesh


class TwoBalloonModel(SolidModel):
    """Two octant shells (n x n x m hexes per patch, three patches each) of one material
    on one cavity. Volumes are those of the octant models (mm^3); ``injected_volume_ul``
    reports the whole of both spheres (8 x the octants' change)."""

    def __init__(self, material: OgdenMaterial, n: int = 2, m: int = 2, element: str = "hex2",
                 bulk_ratio: float = 1000.0, imperfection: float = 0.0,
                 inner_mm: float = INNER_RADIUS_MM, outer_mm: float = OUTER_RADIUS_MM) -> None:
        first = _octant(n, m, inner_mm, outer_mm)
        second = _octant(n, m, inner_mm, outer_mm * (1.0 - imperfection))
        second = MeshHex(TURN @ second.p, second.t)
        sm = shell_mesh(first + second, m, element, inner_mm, outer_mm)
        super().__init__(sm.mesh, element, [(np.arange(sm.mesh.nelements), material, True)],
                         sm.cavity_facets, symmetry_mask, bulk_ratio)
        mid = sm.mesh.p[:, sm.mesh.facets[:, sm.cavity_facets]].mean(axis=1)
        self.balloons = [cav.make_cavity(sm.mesh, element, sm.cavity_facets[side],
                                         self.doflocs)
                         for side in (mid[2] > 0, mid[2] < 0)]
        self.balloon_volume0_mm3 = self.balloon_volumes_mm3(np.zeros(self.n_free))

    def balloon_volumes_mm3(self, u_free: np.ndarray) -> np.ndarray:
        """Cavity volume of each octant model (first, second), mm^3."""
        u = self.full(u_free)
        return np.array([cav.volume(c, u) for c in self.balloons])

    def balloon_stretches(self, u_free: np.ndarray) -> np.ndarray:
        """Inner hoop stretch of each balloon, (v / v0)^(1/3)."""
        return np.cbrt(self.balloon_volumes_mm3(u_free) / self.balloon_volume0_mm3)

    def injected_volume_ul(self, volume_half_mm3: float) -> float:
        return 8.0 * (volume_half_mm3 - self.volume0_mm3)

    def end_face_kinematics(self, u_free: np.ndarray) -> tuple[float, np.ndarray]:
        """No bending here: angle 0 and a zero 'tip' (the stepping records them)."""
        return 0.0, np.zeros(2)

    def tip_force_mn(self, ev: Evaluation) -> float:
        return float("nan")
