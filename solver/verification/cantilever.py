"""A slender cantilever under a small end load, and its beam-theory tip deflection.

Bar 0 <= x <= L, 0 <= y <= b, 0 <= z <= h (mm), clamped at x = 0 (u = 0), a total
transverse load P (uN) in +z on the end face x = L as a uniform traction P / (b h)
integrated consistently with the element's shape functions (a dead load).

Beam theory (small deflection, linear elastic: the Ogden solid's small-strain
limit has shear modulus G = mu0 and, with the volumetric term K/2 (J - 1)^2,
E = 9 K G / (3 K + G), nu = (3 K - 2 G) / (6 K + 2 G), i.e. E -> 3 mu0)::

    Euler-Bernoulli   w = P L^3 / (3 E I),                      I = b h^3 / 12
    Timoshenko        w = P L^3 / (3 E I) + P L / (kappa G A),  A = b h,
                      kappa = 10 (1 + nu) / (12 + 11 nu)   (rectangle, Cowper 1966)

The 3D clamp (all of x = 0 fixed, no warping, no lateral contraction) differs from
the beam's clamp by a local effect of relative size O(h / L).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import ElementHex1, ElementHex2, FacetBasis, LinearForm, MeshHex


@dataclass(frozen=True)
class BeamTheory:
    """Small-strain elastic constants (Pa) and the reference tip deflections (mm)."""

    E_pa: float
    G_pa: float
    nu: float
    euler_bernoulli_mm: float
    timoshenko_mm: float


def beam_tip_deflection(P_un: float, L_mm: float, b_mm: float, h_mm: float, mu0_pa: float,
                        bulk_ratio: float) -> BeamTheory:
    """Tip deflection of a clamped beam under end load P (uN = Pa mm^2)."""
    G = mu0_pa
    K = bulk_ratio * mu0_pa
    E = 9.0 * K * G / (3.0 * K + G)
    nu = (3.0 * K - 2.0 * G) / (6.0 * K + 2.0 * G)
    inertia = b_mm * h_mm**3 / 12.0
    area = b_mm * h_mm
    kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)
    w_eb = P_un * L_mm**3 / (3.0 * E * inertia)
    return BeamTheory(E, G, nu, w_eb, w_eb + P_un * L_mm / (kappa * G * area))


def bar_mesh(L_mm: float, b_mm: float, h_mm: float, nx: int, ny: int, nz: int) -> MeshHex:
    return MeshHex.init_tensor(np.linspace(0.0, L_mm, nx + 1), np.linspace(0.0, b_mm, ny + 1),
                               np.linspace(0.0, h_mm, nz + 1))


def clamp_mask(X: np.ndarray) -> np.ndarray:
    """All components fixed on x = 0; X (3, nnodes) -> (nnodes, 3)."""
    return np.repeat((X[0] < 1e-9)[:, None], 3, axis=1)


def end_load(mesh: MeshHex, element: str, P_un: float, L_mm: float, b_mm: float, h_mm: float
             ) -> np.ndarray:
    """Consistent nodal forces (uN, full vector, dof 3 node + 2) of a uniform +z
    traction P / (b h) on the face x = L."""
    facets = mesh.facets_satisfying(lambda x: np.abs(x[0] - L_mm) < 1e-9, boundaries_only=True)
    elem = ElementHex2() if element == "hex2" else ElementHex1()
    fb = FacetBasis(mesh, elem, facets=facets)
    traction = P_un / (b_mm * h_mm)

    @LinearForm
    def load(v, _):
        return traction * v

    fz = load.assemble(fb)
    f = np.zeros(3 * len(fz))
    f[2::3] = fz
    return f
