"""Inflation of a thick-walled hollow sphere: exact incompressible curve and an octant mesh.

Exact solution (incompressible, isotropic hyperelastic, radial inflation)
--------------------------------------------------------------------------
A material point at reference radius R moves to r(R) with r^3 - R^3 = a^3 - A^3
(volume conservation), so the hoop stretch is lam = r / R and the radial stretch
lam^-2. Let w(lam) = W(lam, lam, lam^-2). The principal Cauchy stresses satisfy
sigma_theta - sigma_r = lam w'(lam) / 2, and radial equilibrium,
d sigma_r / dr + 2 (sigma_r - sigma_theta) / r = 0 with sigma_r(a) = -p and
sigma_r(b) = 0, gives p = int_a^b lam w'(lam) / r dr. With c = a^3 - A^3,
lam^3 - 1 = c / R^3 and d lam / dr = -lam (lam^3 - 1) / r, hence::

    p(lam_a) = int_{lam_b}^{lam_a} w'(lam) / (lam^3 - 1) d lam,
    lam_b^3 = 1 + (lam_a^3 - 1) (A / B)^3.

For Ogden, w(lam) = sum_p mu_p / alpha_p (2 lam^alpha_p + lam^(-2 alpha_p) - 3) and
w'(lam) = 2 sum_p mu_p (lam^(alpha_p - 1) - lam^(-2 alpha_p - 1)). The integrand
tends to 4 mu0 / 3 ... finite as lam -> 1 (w' ~ 12 mu0 (lam - 1)); quad never
evaluates the end points. Derivation: docs/verification-references.md.

Mesh
----
The octant 0 <= x, y, z of the shell A <= |X| <= B as three cube-sphere patches
(the parts of the octant nearest the x, y and z axes), each an n x n x m grid
mapped by X = rho * d / |d|, d = (1, tan(pi xi / 4), tan(pi eta / 4)) cyclically
permuted, merged with duplicate nodes removed. For hex2 the 27-node geometry puts
every higher-order node at the mean radius of the vertices it interpolates, on
the ray through its straight-sided position (so the inner and outer surfaces are
quadratic interpolants of the spheres).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import quad
from skfem import MeshHex, MeshHex2

from solver.materials import OgdenMaterial

INNER_RADIUS_MM = 1.0
OUTER_RADIUS_MM = 1.5


def hoop_energy_derivative(lam: float | np.ndarray, material: OgdenMaterial
                           ) -> float | np.ndarray:
    """w'(lam) for w(lam) = W(lam, lam, lam^-2), Pa (Ogden, mu in kPa -> Pa)."""
    lam = np.asarray(lam, dtype=float)
    return sum(2.0 * m * (lam ** (a - 1.0) - lam ** (-2.0 * a - 1.0))
               for m, a in zip(material.mu_pa, material.alpha))


def outer_stretch(lam_a: float, inner_mm: float = INNER_RADIUS_MM,
                  outer_mm: float = OUTER_RADIUS_MM) -> float:
    """Hoop stretch at the outer surface for inner stretch lam_a (incompressible)."""
    return float((1.0 + (lam_a**3 - 1.0) * (inner_mm / outer_mm) ** 3) ** (1.0 / 3.0))


def exact_pressure_pa(lam_a: float, material: OgdenMaterial, inner_mm: float = INNER_RADIUS_MM,
                      outer_mm: float = OUTER_RADIUS_MM) -> float:
    """Internal pressure (Pa) that inflates the incompressible sphere to inner stretch lam_a."""
    if lam_a == 1.0:
        return 0.0
    lam_b = outer_stretch(lam_a, inner_mm, outer_mm)

    def integrand(lam: float) -> float:
        return float(hoop_energy_derivative(lam, material)) / (lam**3 - 1.0)

    value, _ = quad(integrand, lam_b, lam_a, epsabs=0.0, epsrel=1e-12, limit=200)
    return float(value)


@dataclass(frozen=True)
class SphereMesh:
    """Octant shell mesh; lengths in mm."""

    mesh: MeshHex               # MeshHex (hex1) or MeshHex2 (hex2)
    cavity_facets: np.ndarray   # boundary facets on the inner sphere
    inner_mm: float
    outer_mm: float


def _patch(axis: int, n: int, m: int, inner_mm: float, outer_mm: float) -> MeshHex:
    s = np.linspace(0.0, 1.0, n + 1)
    rho = np.linspace(inner_mm, outer_mm, m + 1)
    box = MeshHex.init_tensor(s, s, rho)
    xi, eta, r = box.p
    d = np.stack([np.ones_like(xi), np.tan(0.25 * np.pi * xi), np.tan(0.25 * np.pi * eta)])
    d = np.roll(d, axis, axis=0)           # cyclic: keeps the orientation
    return MeshHex(r * d / np.linalg.norm(d, axis=0), box.t)


def octant_shell_mesh(n: int = 2, m: int = 2, element: str = "hex2",
                      inner_mm: float = INNER_RADIUS_MM, outer_mm: float = OUTER_RADIUS_MM
                      ) -> SphereMesh:
    """Octant of a thick spherical shell: 3 patches of n x n (around) x m (through) hexes."""
    mesh = _patch(0, n, m, inner_mm, outer_mm)
    for axis in (1, 2):
        mesh = mesh + _patch(axis, n, m, inner_mm, outer_mm)
    return shell_mesh(mesh, m, element, inner_mm, outer_mm)


def shell_mesh(mesh: MeshHex, m: int, element: str, inner_mm: float, outer_mm: float
               ) -> SphereMesh:
    """The trilinear shell mesh ``mesh`` (m elements through the wall, centred at the
    origin) as a ``SphereMesh`` of ``element``, with its inner surface as the cavity."""
    if element == "hex2":
        straight = MeshHex2.from_mesh(mesh).doflocs
        radius = np.linalg.norm(mesh.p, axis=0)
        # Interpolate the vertex radii with the same (trilinear) map: the mean radius.
        mean_r = MeshHex2.from_mesh(MeshHex(np.tile(radius, (3, 1)), mesh.t)).doflocs[0]
        mesh = MeshHex2(straight / np.linalg.norm(straight, axis=0) * mean_r, mesh.t)
    bf = mesh.boundary_facets()
    mid_r = np.linalg.norm(mesh.p[:, mesh.facets[:, bf]].mean(axis=1), axis=0)
    on_inner = np.abs(mid_r - inner_mm) < 0.25 * (outer_mm - inner_mm) / m
    return SphereMesh(mesh, bf[on_inner], inner_mm, outer_mm)


def symmetry_mask(X: np.ndarray) -> np.ndarray:
    """u_i = 0 on the plane X_i = 0 (octant symmetry); X (3, nnodes) -> (nnodes, 3)."""
    return (np.abs(X) < 1e-9).T
