"""The fluid cavity: its volume, and the exact first and second derivatives.

With the chamber walls parametrised over the reference faces (N the cavity's
outward normal, i.e. minus the solid's, and reference tangents e1 x e2 = N)::

    V(x) = 1/3 int_Gamma0 x . (x,1 x x,2) dA         (x,s = dx/dX . e_s)

is the enclosed (half) volume; on the symmetry plane x . n = 0, so the open side
adds nothing. A follower pressure p on the walls does virtual work p dV, so the
load vector is p dV/du and the load stiffness p d2V/du2, which is symmetric.
With the trilinear form T(a, b, c) = a . (b x c)::

    dV[d]      = 1/3 int T(d, x1, x2) + T(x, d1, x2) + T(x, x1, d2)
    d2V[d, D]  = 1/3 int T(d, D1, x2) + T(d, x1, D2) + T(D, d1, x2)
                        + T(x, d1, D2) + T(D, x1, d2) + T(x, D1, d2)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import ElementHex1, ElementHex2, FacetBasis

EPS = np.zeros((3, 3, 3))
EPS[0, 1, 2] = EPS[1, 2, 0] = EPS[2, 0, 1] = 1.0
EPS[0, 2, 1] = EPS[2, 1, 0] = EPS[1, 0, 2] = -1.0


@dataclass
class Cavity:
    N: np.ndarray       # (nf, nq, nb) shape values on the faces
    N1: np.ndarray      # (nf, nq, nb) derivative along e1
    N2: np.ndarray      # (nf, nq, nb) derivative along e2
    wdA: np.ndarray     # (nf, nq)
    dofs: np.ndarray    # (nf, 3 nb) global vector dofs
    X: np.ndarray       # (nf, nb, 3) reference positions of the element's nodes


def make_cavity(mesh, element: str, facets: np.ndarray, doflocs: np.ndarray) -> Cavity:
    elem = ElementHex2() if element == "hex2" else ElementHex1()
    fb = FacetBasis(mesh, elem, facets=facets, intorder=5 if element == "hex2" else 3)
    nb = fb.Nbfun
    # The solid's outward normal points into the cavity; the cavity's own outward
    # normal N (the one the volume integral needs) is its negative. Tangents
    # t1, t2 with t1 x t2 = N at every quadrature point.
    N = -np.moveaxis(fb.normals, 0, -1)                              # (nf, nq, 3)
    helper = np.where(np.abs(N[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    t1 = np.cross(helper, N)
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    t2 = np.cross(N, t1)
    vals = np.stack([fb.basis[a][0].value for a in range(nb)], axis=-1)       # (nf, nq, nb)
    grads = np.stack([fb.basis[a][0].grad for a in range(nb)], axis=-1)       # (3, nf, nq, nb)
    N1 = np.einsum("jfqa,fqj->fqa", grads, t1)
    N2 = np.einsum("jfqa,fqj->fqa", grads, t2)
    sdofs = fb.element_dofs.T                                                 # (nf, nb)
    # Keep the shape functions of the face's own nodes (9 of hex2's 27, 4 of hex1's 8):
    # the others vanish on the face with their tangential derivatives (skfem evaluates
    # them to ~1e-13), so the cavity's vectors and matrices are 9x smaller for hex2.
    on_face = np.abs(vals).max(axis=1) > 1e-8                                 # (nf, nb)
    n_face = int(on_face.sum(axis=1).min())
    if n_face == on_face.sum(axis=1).max():
        keep = np.argsort(~on_face, axis=1, kind="stable")[:, :n_face]       # (nf, n_face)
        vals, N1, N2 = (np.take_along_axis(x, keep[:, None, :], axis=2) for x in (vals, N1, N2))
        sdofs = np.take_along_axis(sdofs, keep, axis=1)
        nb = n_face
    dofs = (3 * sdofs[:, :, None] + np.arange(3)).reshape(sdofs.shape[0], 3 * nb)
    return Cavity(vals, N1, N2, fb.dx, dofs, doflocs[:, sdofs].transpose(1, 2, 0))


def _positions(cav: Cavity, u: np.ndarray):
    xe = cav.X + u[cav.dofs].reshape(cav.X.shape)                    # (nf, nb, 3)
    x = np.einsum("fqa,fai->fqi", cav.N, xe)
    x1 = np.einsum("fqa,fai->fqi", cav.N1, xe)
    x2 = np.einsum("fqa,fai->fqi", cav.N2, xe)
    return x, x1, x2


def volume(cav: Cavity, u: np.ndarray) -> float:
    """Enclosed half volume, mm^3."""
    x, x1, x2 = _positions(cav, u)
    return float((np.einsum("fqi,fqi->fq", x, np.cross(x1, x2)) * cav.wdA).sum() / 3.0)


def volume_gradient(cav: Cavity, u: np.ndarray) -> np.ndarray:
    """dV/du per facet, (nf, 3 nb)."""
    x, x1, x2 = _positions(cav, u)
    w = cav.wdA / 3.0
    g = (np.einsum("fqa,fqi,fq->fai", cav.N, np.cross(x1, x2), w)
         + np.einsum("fqa,fqi,fq->fai", cav.N1, np.cross(x2, x), w)
         + np.einsum("fqa,fqi,fq->fai", cav.N2, np.cross(x, x1), w))
    return g.reshape(g.shape[0], -1)


def volume_hessian(cav: Cavity, u: np.ndarray) -> np.ndarray:
    """d2V/du2 per facet, (nf, 3 nb, 3 nb), symmetric."""
    x, x1, x2 = _positions(cav, u)
    w = cav.wdA / 3.0
    E = EPS
    # Each term: shape products (a, b) times an antisymmetric 3x3 in (i, k).
    ex2 = np.einsum("ikm,fqm->fqik", E, x2)
    ex1 = np.einsum("imk,fqm->fqik", E, x1)
    ex = np.einsum("mik,fqm->fqik", E, x)
    H = (np.einsum("fqa,fqb,fqik,fq->faibk", cav.N, cav.N1, ex2, w, optimize=True)
         + np.einsum("fqa,fqb,fqik,fq->faibk", cav.N, cav.N2, ex1, w, optimize=True)
         + np.einsum("fqa,fqb,fqik,fq->faibk", cav.N1, cav.N2, ex, w, optimize=True))
    H = H + H.transpose(0, 3, 4, 1, 2)
    nf, nb = H.shape[0], H.shape[1]
    return H.reshape(nf, 3 * nb, 3 * nb)
