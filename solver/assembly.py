"""Vectorised total-Lagrangian assembly of the nearly incompressible Ogden solid.

Energy of the body (reference configuration, lengths mm, stresses Pa, energy nJ)::

    Pi(u) = sum_e [ int_e W_iso(F) dV + K/2 * g_e^T M_e^-1 g_e ],
    g_e = int_e N_p (J - 1) dV,   M_e = int_e N_p N_p^T dV

The volumetric term is the L2 projection of the dilatation J - 1 onto a pressure
space that is discontinuous between elements (constant for hex1: mean dilatation;
linear for hex2: the inf-sup stable Q2/P1-disc pair), i.e. the statically
condensed mixed u-p element. It removes volumetric locking while the whole scheme
stays a single symmetric energy, so the tangent is its exact Hessian.

Pressure field p_hat = N_p . K M_e^-1 g_e, and

    residual   r = int (P_iso + p_hat cof F) : grad(du) dV
    tangent    K = int grad(du) : (A_iso + p_hat J (f f - f (x) f)^T) : grad(Du) dV
                   + K sum_e D_e^T M_e^-1 D_e,     D_e = int N_p cof F : grad(.) dV

with f = F^-T. Element matrices are scattered into a CSR pattern computed once,
restricted to the free degrees of freedom.

Newton iterates the mixed form rather than the penalty: the element pressures q_e
(coefficients of p_hat in N_p) are a state of their own, with the constraint

    R_p = g_e - M_e q_e / K = 0,

condensed element by element. Its linearisation gives the same matrix as above with
p_hat = N_p . q_e in the geometric term, the condensed residual

    r_c = r + K D_e^T M_e^-1 R_p,

and the pressure update dq_e = K M_e^-1 (R_p + D_e du_e). At R_p = 0 (q_e = K M_e^-1 g_e,
which is what ``pressure_coef=None`` evaluates) everything equals the penalty form.
The difference is in the iterates: after a large predictor step a rotated element
shows a spurious second-order dilatation, and the penalty turns it into a pressure
K (J - 1) that swamps the geometric stiffness and makes the tangent indefinite;
the mixed iterate keeps the linearised, physical pressure (docs/physics.md).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementHex1, ElementHex2

from solver.ogden import stress_and_tangent
from solver.parallel import map_pair


@dataclass
class MaterialBlock:
    """The elements of one material, with everything precomputed for assembly."""

    mu_pa: np.ndarray           # Ogden terms
    alpha: np.ndarray
    bulk_pa: float              # K
    dN: np.ndarray              # (ne, nq, nb, 3) shape-function gradients
    wdV: np.ndarray             # (ne, nq) quadrature weight x det J
    Np: np.ndarray              # (ne, nq, npr) pressure basis
    Minv: np.ndarray            # (ne, npr, npr)
    dofs: np.ndarray            # (ne, 3 nb) global vector dofs, local order 3 a + i
    membrane: bool
    elements: np.ndarray | None = None      # element indices in the mesh
    box_scale: np.ndarray | None = None     # (ne, 3) element sizes when all are boxes
    box_products: np.ndarray | None = None  # (nb nb, nq 9): dNref_aJ dNref_bL per q
    box_gradients: np.ndarray | None = None  # (nb, nq 3): dNref_aJ, columns (q J)
    M: np.ndarray | None = None             # (ne, npr, npr) pressure mass matrices


def make_basis(mesh, element: str, intorder: int | None = None) -> Basis:
    if element == "hex2":
        return Basis(mesh, ElementHex2(), intorder=intorder or 5)
    return Basis(mesh, ElementHex1(), intorder=intorder or 3)


def material_block(basis: Basis, elements: np.ndarray, mu_pa, alpha, bulk_pa: float,
                   pressure_order: int, membrane: bool) -> MaterialBlock:
    """Gather the shape-function data of ``elements`` from a scalar Basis."""
    nb = basis.Nbfun
    grads = np.stack([basis.basis[a][0].grad for a in range(nb)], axis=0)  # (nb, 3, ne, nq)
    dN = np.transpose(grads, (2, 3, 0, 1))[elements]
    wdV = basis.dx[elements]
    X = basis.mapping.F(basis.X)[:, elements]                               # (3, ne, nq)
    if pressure_order == 0:
        Np = np.ones(wdV.shape + (1,))
    else:
        centre = (X * wdV).sum(axis=-1, keepdims=True) / wdV.sum(axis=-1)[:, None]
        size = X.max(axis=-1, keepdims=True) - X.min(axis=-1, keepdims=True)
        xi = (X - centre) / np.where(size > 0, size, 1.0)
        Np = np.concatenate([np.ones(wdV.shape + (1,)), np.moveaxis(xi, 0, -1)], axis=-1)
    M = np.einsum("eqm,eqn,eq->emn", Np, Np, wdV)
    sdofs = basis.element_dofs[:, elements].T                               # (ne, nb)
    dofs = (3 * sdofs[:, :, None] + np.arange(3)).reshape(len(elements), 3 * nb)
    block = MaterialBlock(np.asarray(mu_pa, float), np.asarray(alpha, float), float(bulk_pa),
                          dN, wdV, Np, np.linalg.inv(M), dofs, membrane, elements, M=M)
    _detect_boxes(block)
    return block


def sub_block(block: MaterialBlock, elements: slice) -> MaterialBlock:
    """The block restricted to a range of its elements (views, no copies)."""
    def cut(x):
        return None if x is None else x[elements]
    return replace(block, dN=block.dN[elements], wdV=block.wdV[elements],
                   Np=block.Np[elements], Minv=block.Minv[elements],
                   dofs=block.dofs[elements], elements=cut(block.elements),
                   box_scale=cut(block.box_scale), M=cut(block.M))


def _detect_boxes(block: MaterialBlock) -> None:
    """Enable the fast path when every element is an axis-aligned box of the same
    reference shape functions, i.e. dN[e] = dN[0] * h[0] / h[e] per direction."""
    dN = block.dN
    if dN.shape[0] == 0:
        return
    ref = dN[0]
    scale_ref = np.abs(ref).max(axis=(0, 1))                                   # per J
    scale = np.abs(dN).max(axis=(1, 2))                                        # (ne, 3)
    ratio = scale_ref / scale                                                  # h_e / h_0
    predicted = ref[None] / ratio[:, None, None, :]
    if not np.allclose(predicted, dN, rtol=1e-10, atol=1e-12 * float(scale.max())):
        return
    # dN[e] = dNref / h with dNref = ref * h0; take h0 = 1 so h = ratio.
    nq, nb = ref.shape[0], ref.shape[1]
    prod = np.einsum("qaJ,qbL->abqJL", ref, ref).reshape(nb * nb, nq * 9)
    block.box_scale = ratio
    block.box_products = prod
    block.box_gradients = np.ascontiguousarray(ref.transpose(1, 0, 2).reshape(nb, nq * 3))


def _gradient_contraction(block: MaterialBlock, X: np.ndarray) -> np.ndarray:
    """sum_(q, J) dN[e, q, a, J] X[e, q, ..., J] -> (ne, nb, ...): the transpose of the
    gradient, for residuals (X = P dV) and the pressure coupling D (X = N_p cof dV).
    On box elements one matrix product with the common reference gradients."""
    ne, nq = X.shape[:2]
    if block.box_gradients is not None:
        # X_J / h_J laid out as (q, J, e, ...) in one pass, then one matrix product.
        rest = X.shape[2:-1]
        Xs = np.empty((nq, 3, ne) + rest)
        inv_h = (1.0 / block.box_scale).T.reshape((1, 3, ne) + (1,) * len(rest))
        np.multiply(np.moveaxis(X, (1, -1), (0, 1)), inv_h, out=Xs)
        Y = block.box_gradients @ Xs.reshape(nq * 3, -1)                    # (a, e ...)
        return np.moveaxis(Y.reshape((-1, ne) + rest), 0, 1)
    return np.einsum("eqaJ,eq...J->ea...", block.dN, X, optimize=True)


def cofactor_and_det(F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cof F = det(F) F^-T (rows: cross products of F's rows) and det F, for (..., 3, 3)."""
    r0, r1, r2 = F[..., 0, :], F[..., 1, :], F[..., 2, :]
    cof = np.stack((np.cross(r1, r2), np.cross(r2, r0), np.cross(r0, r1)), axis=-2)
    return cof, np.einsum("...j,...j->...", r0, cof[..., 0, :])


def node_pairs(nb: int) -> tuple[np.ndarray, np.ndarray]:
    """The node pairs (a, b) with a <= b of an element with nb nodes: the blocks of
    the symmetric element matrix that are computed and stored."""
    a, b = np.triu_indices(nb)
    return a, b


def element_stiffness(block: MaterialBlock, A: np.ndarray,
                      weights: np.ndarray | None = None) -> np.ndarray:
    """K_e[a i, b k] = sum_q dN_aJ A_iJkL dN_bL w_q for tangents A (ne, nq, 9, 9),
    symmetric under (iJ) <-> (kL), times ``weights`` (ne, nq) when given (A is then
    not modified). Returned in the symmetric pair layout
    (npairs, ne, 3, 3): the 3 x 3 block of node pair (a, b), a <= b (``node_pairs``),
    K_e[b k, a i] being its transpose.

    On axis-aligned box elements (our tensor-product meshes) dN = dN_ref / h_J, so
    the shape-function products are common to all elements and the whole
    contraction is one large matrix product; otherwise a loop over quadrature points.
    """
    ne, nq, nb, _ = block.dN.shape
    pa, pb = node_pairs(nb)
    if block.box_scale is not None:
        h = block.box_scale                                                   # (ne, 3)
        scale = 1.0 / (h[:, None, :, None] * h[:, None, None, :])             # (e, 1, J, L)
        if weights is not None:
            scale = scale * weights[:, :, None, None]                         # (e, q, J, L)
        # Scaled and transposed to (q J L), (e i k) in one pass.
        At = np.empty((nq, 3, 3, ne, 3, 3))
        np.multiply(A.reshape(ne, nq, 3, 3, 3, 3).transpose(1, 3, 5, 0, 2, 4),
                    scale.transpose(1, 2, 3, 0)[..., None, None], out=At)
        prod = block.box_products.reshape(nb, nb, nq * 9)[pa, pb]             # (pairs, q J L)
        return (prod @ At.reshape(nq * 9, ne * 9)).reshape(len(pa), ne, 3, 3)
    if weights is not None:
        A = A * weights[..., None, None]
    K = np.zeros((ne, nb, 3, nb, 3))
    A4 = A.reshape(ne, nq, 3, 3, 3, 3)
    for q in range(nq):
        C = np.einsum("eaJ,eiJkL->eaikL", block.dN[:, q], A4[:, q], optimize=True)
        K += np.einsum("eaikL,ebL->eaibk", C, block.dN[:, q], optimize=True)
    return np.ascontiguousarray(K[:, pa, :, pb, :])    # (pairs, ne, 3, 3)


@functools.cache
def _pair_entries(nb: int) -> np.ndarray:
    """Flat indices (a i) 3 nb + (b k) of the pair layout's entries in a full
    (3 nb x 3 nb) element matrix, in the order (pair, i, k)."""
    pa, pb = node_pairs(nb)
    i3 = np.arange(3)
    rows = 3 * pa[:, None, None] + i3[None, :, None]
    cols = 3 * pb[:, None, None] + i3[None, None, :]
    return (rows * 3 * nb + cols).ravel()


def full_element_matrices(pairs: np.ndarray) -> np.ndarray:
    """(ne, 3 nb, 3 nb) element matrices from the symmetric pair layout."""
    npairs, ne = pairs.shape[:2]
    nb = int(round((np.sqrt(8 * npairs + 1) - 1) / 2))
    pa, pb = node_pairs(nb)
    K = np.zeros((ne, nb, 3, nb, 3))
    K[:, pb, :, pa, :] = np.swapaxes(pairs, -1, -2)
    K[:, pa, :, pb, :] = pairs
    return K.reshape(ne, 3 * nb, 3 * nb)


def deformation_gradient(block: MaterialBlock, u: np.ndarray) -> np.ndarray:
    """F = I + grad u at every quadrature point, (ne, nq, 3, 3)."""
    ne = block.dofs.shape[0]
    ue = u[block.dofs].reshape(ne, -1, 3)                                   # (ne, nb, 3)
    if block.box_gradients is not None:
        nq = block.dN.shape[1]
        G = (ue.transpose(0, 2, 1).reshape(ne * 3, -1) @ block.box_gradients)  # (e i, q J)
        G = G.reshape(ne, 3, nq, 3).transpose(0, 2, 1, 3) / block.box_scale[:, None, None, :]
        G[..., 0, 0] += 1.0
        G[..., 1, 1] += 1.0
        G[..., 2, 2] += 1.0
        return G
    return np.eye(3) + np.einsum("eai,eqaJ->eqiJ", ue, block.dN)


@dataclass
class BlockState:
    energy: float
    residual: np.ndarray      # (ne, 3 nb); condensed (r_c) when pressures were given
    stiffness: np.ndarray | None   # (npairs, ne, 3, 3): symmetric pair layout
    lam_max: np.ndarray       # (ne, nq)
    min_J: float
    constraint: np.ndarray | None = None        # (ne, npr) R_p = g - M q / K
    D: np.ndarray | None = None                 # (ne, npr, 3 nb)
    dilatation_error: float = 0.0               # max |M^-1 R_p| (a strain)


def consistent_pressures(block: MaterialBlock, u: np.ndarray) -> np.ndarray:
    """q_e = K M_e^-1 g_e: the element pressures (Pa) of the penalty form at u."""
    F = deformation_gradient(block, u)
    g = np.einsum("eqm,eq,eq->em", block.Np, np.linalg.det(F) - 1.0, block.wdV)
    return block.bulk_pa * np.einsum("emn,en->em", block.Minv, g)


def pressure_update(block: MaterialBlock, state: BlockState, du: np.ndarray,
                    constraint: bool = True) -> np.ndarray:
    """dq_e = K M_e^-1 (R_p + D_e du_e) for a full displacement update du (mm);
    ``constraint=False`` drops R_p: the pressures' rate K M_e^-1 D_e du_e along a
    displacement rate du (the tangent of the equilibrium path)."""
    assert state.constraint is not None and state.D is not None
    due = du[block.dofs]                                                    # (ne, 3 nb)
    rhs = np.einsum("ema,ea->em", state.D, due)
    if constraint:
        rhs += state.constraint
    return block.bulk_pa * np.einsum("emn,en->em", block.Minv, rhs)


def evaluate_block(block: MaterialBlock, u: np.ndarray, with_tangent: bool = True,
                   pressure_coef: np.ndarray | None = None) -> BlockState:
    """Energy, element residuals and (optionally) element tangents of one block.

    ``pressure_coef`` (ne, npr, Pa): the mixed iterate's element pressures; None for
    the penalty form (pressures consistent with u, R_p = 0).
    """
    F = deformation_gradient(block, u)
    ne, nq = F.shape[:2]
    cof, J = cofactor_and_det(F)
    if not np.all(J > 0):
        raise FloatingPointError("element inverted (det F <= 0)")
    W, P, A, lam = stress_and_tangent(F, block.mu_pa, block.alpha, tangent=with_tangent)

    g = np.einsum("eqm,eq,eq->em", block.Np, J - 1.0, block.wdV)
    constraint: np.ndarray | None = None
    if pressure_coef is not None:
        coef = pressure_coef
        assert block.M is not None                        # set by material_block
        Mq = np.einsum("emn,en->em", block.M, coef)                           # M_e q_e
        Rp = g - Mq / block.bulk_pa
        constraint = Rp
        # Mixed functional int W + q.g - q.M.q / 2K (equals the penalty energy at R_p = 0).
        energy = float((W * block.wdV).sum() + np.einsum("em,em->", coef, g)
                       - 0.5 * np.einsum("em,em->", coef, Mq) / block.bulk_pa)
    else:
        coef = block.bulk_pa * np.einsum("emn,en->em", block.Minv, g)
        energy = float((W * block.wdV).sum() + 0.5 * np.einsum("em,em->", g, coef))
    p_hat = np.einsum("eqm,em->eq", block.Np, coef)

    Ptot = P + p_hat[..., None, None] * cof
    Ptot *= block.wdV[..., None, None]
    nb = block.dN.shape[2]
    r = _gradient_contraction(block, Ptot).reshape(ne, 3 * nb)              # (e, a i)
    D = None
    if pressure_coef is not None or with_tangent:
        # D_e[m, a i] = int N_p,m cof_iJ dN_aJ dV
        NpW = block.Np * block.wdV[..., None]                                 # (e, q, m)
        D = _gradient_contraction(block, NpW[..., :, None, None] * cof[:, :, None])
        D = np.ascontiguousarray(D.transpose(0, 2, 1, 3)).reshape(ne, -1, 3 * nb)
    if pressure_coef is not None:
        strain = np.einsum("emn,en->em", block.Minv, Rp)                      # M^-1 R_p
        r = r + np.einsum("ema,em->ea", D, block.bulk_pa * strain)
        dilatation_error = float(np.abs(strain).max()) if strain.size else 0.0
    else:
        dilatation_error = 0.0
    if not with_tangent:
        return BlockState(energy, r, None, lam, float(J.min()), constraint, D,
                          dilatation_error)

    # + p_hat J (f_iJ f_kL - f_iL f_kJ) = p_hat d cof_iJ / d F_kL = p_hat e_ikm e_JLN F_mN
    # (f = F^-T): 36 entries of the 81, where i != k and J != L.
    A.reshape(ne, nq, 81)[..., _COF_SLOTS] += (
        p_hat[..., None] * F.reshape(ne, nq, 9)[..., _COF_SOURCES]) * _COF_SIGNS
    K = element_stiffness(block, A, block.wdV)
    # + K D^T M^-1 D: the element's (3 nb x 3 nb) products (one small matrix product
    # each), their node-pair blocks a <= b gathered into the pair layout.
    # In chunks of 96 elements: the full products take twice the pair layout's memory.
    G = block.bulk_pa * (block.Minv @ D)
    for start in range(0, ne, 96):
        c = slice(start, min(start + 96, ne))
        KD = np.swapaxes(D[c], 1, 2) @ G[c]                                  # (e, a i, b k)
        KD = np.take(KD.reshape(c.stop - c.start, -1), _pair_entries(nb), axis=1, mode="clip")
        K[:, c] += KD.reshape(c.stop - c.start, -1, 3, 3).transpose(1, 0, 2, 3)
    return BlockState(energy, r, K, lam, float(J.min()), constraint, D, dilatation_error)


def _cofactor_derivative_slots() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """d cof_iJ / d F_kL = e_ikm e_JLN F_mN as (slot 9 (3 i + J) + 3 k + L of the
    flattened tangent, source 3 m + N in F, sign) over its 36 non-zero entries."""
    slots, sources, signs = [], [], []
    perm = {(0, 1): (2, 1.0), (1, 2): (0, 1.0), (2, 0): (1, 1.0),
            (1, 0): (2, -1.0), (2, 1): (0, -1.0), (0, 2): (1, -1.0)}
    for (i, k), (m, s1) in perm.items():
        for (J, L), (n, s2) in perm.items():
            slots.append(9 * (3 * i + J) + 3 * k + L)
            sources.append(3 * m + n)
            signs.append(s1 * s2)
    return np.array(slots), np.array(sources), np.array(signs)


_COF_SLOTS, _COF_SOURCES, _COF_SIGNS = _cofactor_derivative_slots()


class Pattern:
    """CSR pattern of a set of element dof lists, restricted to free dofs.

    Material blocks (the first ``n_pair_lists`` dof lists, 3 nb dofs per element) give
    their element matrices in the symmetric pair layout of ``element_stiffness``; the
    others (cavity, spring) as full, symmetric (ne, m, m) matrices.
    ``reduced[g]`` is the index of global dof g among the free dofs, or -1.

    The values are summed into the upper triangle only and mirrored into the full
    matrix by one gather (half the scatter's work and memory).
    """

    def __init__(self, dof_lists: list[np.ndarray], free: np.ndarray, ndofs: int,
                 n_pair_lists: int = 0, groups: list[tuple[int, int]] | None = None) -> None:
        """``groups``: ranges (start, stop) of consecutive dof lists whose values are
        scattered together (``upper_values``); default one group of all lists."""
        self.ndofs = ndofs
        self.free = free
        reduced = -np.ones(ndofs, dtype=np.int64)
        reduced[free] = np.arange(len(free))
        self.reduced = reduced
        n = len(free)
        self.n = n
        # Keys row * n + col of the upper-triangle slot each value adds to (-1 where a
        # fixed dof is involved, or for the lower half of a block that is stored in
        # full), int32 when they fit (the set-up's memory).
        kind = np.int32 if n * n < 2**31 else np.int64
        rdofs = reduced.astype(kind)
        keys = []
        for index, dofs in enumerate(dof_lists):
            rd = rdofs[dofs]                                                # (ne, m)
            if index < n_pair_lists:
                nb = rd.shape[1] // 3
                pa, pb = node_pairs(nb)
                r3 = rd.reshape(-1, nb, 3)
                rows = r3[:, pa, :, None].transpose(1, 0, 2, 3)            # (P, ne, 3, 1)
                cols = r3[:, pb, None, :].transpose(1, 0, 2, 3)            # (P, ne, 1, 3)
                # A pair a < b feeds (r, c) and (c, r): its upper slot is (min, max); a
                # block a = b is stored in full, so only its upper half counts.
                low, high = np.minimum(rows, cols), np.maximum(rows, cols)
                ok = (low >= 0) & ((pa != pb)[:, None, None, None] | (rows <= cols))
            else:
                rows, cols = rd[:, :, None], rd[:, None, :]
                low, high = rows, cols
                ok = (rows >= 0) & (cols >= 0) & (rows <= cols)
            keys.append(np.where(ok, low * n + high, -1).ravel())
            del rows, cols, low, high, ok
        sizes = [len(k) for k in keys]
        keys = np.concatenate(keys)
        # One sort of all keys gives the pattern and the scatter of values into it: the
        # scatter is one sparse (nnz x values) 0/1 matrix, data = S @ values (~2x faster
        # than a bincount per slot list: benchmarks/RESULTS.md, issue 12, third session).
        order = np.argsort(keys, kind="stable")
        keys = keys[order]
        first = int(np.searchsorted(keys, 0))                               # skip the -1s
        keys = keys[first:]
        sources = order[first:].astype(np.int32)
        del order
        new_key = np.empty(len(keys), dtype=bool)
        new_key[:1] = True
        np.not_equal(keys[1:], keys[:-1], out=new_key[1:])
        upper = keys[new_key].astype(np.int64)
        self.n_values = int(sum(sizes))
        # The upper-triangle slot of every value (-1: none), then per group of lists the
        # columns of the 0/1 scatter matrix S in CSC form (one entry per column at most):
        # data = sum over groups of S_g @ values_g.
        target = np.full(self.n_values, -1, dtype=np.int32)
        target[sources] = np.cumsum(new_key, dtype=np.int32) - 1
        del keys, new_key, sources
        self.groups = groups if groups is not None else [(0, len(dof_lists))]
        offsets = np.cumsum([0] + sizes)
        self.group_sizes = [int(offsets[b] - offsets[a]) for a, b in self.groups]
        self.scatter_groups = []
        for a, b in self.groups:
            t = target[offsets[a]:offsets[b]]
            valid = t >= 0
            colptr = np.concatenate(([0], np.cumsum(valid, dtype=np.int32)))
            self.scatter_groups.append(sp.csc_matrix(
                (np.ones(int(colptr[-1])), t[valid], colptr), shape=(len(upper), len(t))))
        del target
        urow, ucol = np.divmod(upper, n)
        # The full pattern: the upper slots and the mirrors of those off the diagonal;
        # full data = upper data[self.mirror].
        off = np.flatnonzero(urow != ucol)
        order = np.argsort(np.concatenate((upper, ucol[off] * n + urow[off])))
        self.mirror = np.concatenate((np.arange(len(upper)), off))[order].astype(np.int32)
        self.indptr, self.indices = _csr_structure(
            np.concatenate((urow, ucol[off]))[order], np.concatenate((ucol, urow[off]))[order], n)
        self.nnz = len(order)

    def upper_values(self, group: int, element_matrices: list[np.ndarray]) -> np.ndarray:
        """The upper triangle's values (CSR order) summed from the element matrices of
        one group of dof lists: a part of ``assemble``'s argument."""
        values = np.concatenate([Ke.ravel() for Ke in element_matrices])
        if len(values) != self.group_sizes[group]:
            raise ValueError(f"{len(values)} element-matrix entries for a group of "
                             f"{self.group_sizes[group]}")
        return self.scatter_groups[group] @ values

    def assemble(self, upper: np.ndarray) -> sp.csr_matrix:
        """The full symmetric matrix from its upper triangle's values, gathered in two
        halves (on two threads when the budget allows)."""
        data = np.empty(self.nnz)
        half = self.nnz // 2
        # (mode "clip" with out: numpy gathers without buffering or an intp index copy)
        map_pair(lambda part: np.take(upper, self.mirror[part], out=data[part], mode="clip"),
                 [slice(0, half), slice(half, self.nnz)])
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def matrix(self, element_matrices: list[np.ndarray]) -> sp.csr_matrix:
        """The full symmetric matrix from the element matrices of all lists."""
        if sum(Ke.size for Ke in element_matrices) != self.n_values:
            raise ValueError(f"{sum(Ke.size for Ke in element_matrices)} element-matrix "
                             f"entries for a pattern of {self.n_values}")
        upper = 0.0
        for g, (a, b) in enumerate(self.groups):
            upper = upper + self.upper_values(g, element_matrices[a:b])
        return self.assemble(upper)


def _csr_structure(rows: np.ndarray, cols: np.ndarray, n: int
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(indptr, indices) of entries sorted by row, then column."""
    indptr = np.concatenate(([0], np.cumsum(np.bincount(rows, minlength=n))))
    return indptr.astype(np.int32), cols.astype(np.int32)


def scatter_vector(ndofs: int, dofs: np.ndarray, values: np.ndarray) -> np.ndarray:
    return np.bincount(dofs.ravel(), weights=values.ravel(), minlength=ndofs)
