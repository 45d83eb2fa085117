"""Isochoric Ogden strain energy: second Piola-Kirchhoff stress and its exact tangent.

For a right Cauchy-Green tensor C with eigenvalues c_i = lambda_i^2 and unit
eigenvectors n_i, the isochoric Ogden energy is a symmetric function of the c_i::

    w(c) = sum_p mu_p / alpha_p * (I3^(-alpha_p/6) * sum_i c_i^(alpha_p/2) - 3),  I3 = c1 c2 c3

(I3^(-alpha/6) c_i^(alpha/2) = lbar_i^alpha, the isochoric stretches). For any such
isotropic energy W(C) = w(c)::

    S = 2 dW/dC = 2 sum_i w_i  n_i (x) n_i
    CC = 4 d2W/dC2:  CC_iijj = 4 w_ij,   CC_ijij = CC_ijji = 2 (S_i - S_j)/(c_i - c_j)  (i != j)

in the eigenbasis. The divided difference (w_i - w_j)/(c_i - c_j) tends to
w_ii - w_ij when c_i -> c_j; it is even in the split, so evaluating the limit at the
mid-point is second-order accurate. We switch to it when the relative split is
below ``REPEATED_TOL`` (which also covers the undeformed state, c = (1, 1, 1)).

Stresses are in the units of mu (Pa in this project). Everything is vectorised
over leading axes.
"""

from __future__ import annotations

import numpy as np

REPEATED_TOL = 1e-6


def energy_derivatives(c: np.ndarray, mu: np.ndarray, alpha: np.ndarray,
                       hessian: bool = True
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """w, its gradient w_i (..., 3) and Hessian w_ij (..., 3, 3) in the eigenvalues c_i
    (None unless ``hessian``).

    ``mu`` and ``alpha`` are 1D arrays of the Ogden terms (mu in Pa).
    """
    c = np.asarray(c, dtype=float)
    w = np.zeros(c.shape[:-1])
    dw = np.zeros(c.shape)
    d2w = np.zeros(c.shape + (3,)) if hessian else None
    log_i3 = np.log(c).sum(axis=-1)
    inv_c = 1.0 / c
    eye = np.eye(3)
    for m, a in zip(mu, alpha):
        s = np.exp(-a / 6.0 * log_i3)                 # I3^(-a/6)
        ca = c ** (0.5 * a)                           # c_i^(a/2)
        phi = ca.sum(axis=-1)
        w += m / a * (s * phi - 3.0)
        # g_i = -phi/(6 c_i) + c_i^(a/2 - 1)/2 ;  w_i = mu s g_i
        g = -phi[..., None] * inv_c / 6.0 + 0.5 * ca * inv_c
        dw += m * s[..., None] * g
        if d2w is None:
            continue
        # dg_i/dc_j = -(a/2) c_j^(a/2-1) / (6 c_i)
        #             + delta_ij (phi / (6 c_i^2) + (a/2 - 1) c_i^(a/2-2) / 2)
        dg = (-(a / 12.0) * (ca * inv_c)[..., None, :] * inv_c[..., :, None]
              + eye * (phi[..., None] * inv_c**2 / 6.0
                       + 0.5 * (0.5 * a - 1.0) * ca * inv_c**2)[..., None])
        # d(s)/dc_j = -(a/6) s / c_j
        d2w += m * s[..., None, None] * (dg - (a / 6.0) * g[..., :, None] * inv_c[..., None, :])
    return w, dw, d2w


def stress_and_tangent(F: np.ndarray, mu: np.ndarray, alpha: np.ndarray,
                       tangent: bool = True
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
    """Isochoric Ogden response at deformation gradients F (..., 3, 3).

    Returns (W, P, A, lam_max): strain energy density, first Piola-Kirchhoff stress
    P = F S (..., 3, 3), the material tangent A_iJkL = dP_iJ/dF_kL as (..., 9, 9)
    with row index 3 i + J (None when ``tangent`` is False: a residual needs only P),
    and the largest principal stretch (...,).
    """
    C = np.swapaxes(F, -1, -2) @ F
    c, Q = np.linalg.eigh(C)
    w, dw, d2w = energy_derivatives(c, mu, alpha, hessian=tangent)
    S_eig = 2.0 * dw                                            # principal PK2 stresses
    S = (Q * S_eig[..., None, :]) @ np.swapaxes(Q, -1, -2)
    P = F @ S
    lam_max = np.sqrt(c[..., -1])
    if not tangent:
        return w, P, None, lam_max

    # Divided differences theta_ab = (w_a - w_b)/(c_a - c_b), limit w_aa - w_ab, for
    # the pairs (a, b) = (0, 1), (0, 2), (1, 2).
    ia, ib = np.array([0, 0, 1]), np.array([1, 2, 2])
    ca, cb = c[..., ia], c[..., ib]
    diff = ca - cb
    repeated = np.abs(diff) <= REPEATED_TOL * np.maximum(np.abs(ca), np.abs(cb))
    theta = (dw[..., ia] - dw[..., ib]) / np.where(repeated, 1.0, diff)
    if np.any(repeated):
        # Evaluate the limit at the mid-point of each near-coincident pair.
        *lead, pair = np.nonzero(repeated)
        a_idx, b_idx = ia[pair], ib[pair]
        c_mid = c[tuple(lead)].copy()
        n = np.arange(c_mid.shape[0])
        mid = 0.5 * (c_mid[n, a_idx] + c_mid[n, b_idx])
        c_mid[n, a_idx] = mid
        c_mid[n, b_idx] = mid
        _, _, h = energy_derivatives(c_mid, mu, alpha)
        theta[(*lead, pair)] = h[n, a_idx, a_idx] - h[n, a_idx, b_idx]

    # With u_a = F n_a and E_ab = u_a (x) n_b flattened to 9 (row 3 i + J), the spectral
    # tangent is sum_ab 4 w_ab E_aa (x) E_bb + sum_(a<b) 2 theta_ab G_ab (x) G_ab,
    # G_ab = E_ab + E_ba: A = H^T X H with the six rows H = (E_00, E_11, E_22, G_01,
    # G_02, G_12) and X = diag(4 w_ab, 2 theta_ab), one batched (9 x 6)(6 x 9) product.
    batch = c.shape[:-1]
    U = F @ Q                                                   # columns u_a
    rows_a = np.array([0, 1, 2, 0, 0, 1])
    rows_b = np.array([0, 1, 2, 1, 2, 2])
    H = U[..., :, None, rows_a] * Q[..., None, :, rows_b]              # (..., i, J, 6)
    H[..., 3:] += U[..., :, None, rows_b[3:]] * Q[..., None, :, rows_a[3:]]
    H = np.swapaxes(H.reshape(batch + (9, 6)), -1, -2)                  # (..., 6, 9)
    XH = np.concatenate((4.0 * d2w @ H[..., :3, :],
                         2.0 * theta[..., :, None] * H[..., 3:, :]), axis=-2)
    A = np.swapaxes(H, -1, -2) @ XH
    # Geometric part delta_ik S_JL.
    A4 = A.reshape(batch + (3, 3, 3, 3))
    for i in range(3):
        A4[..., i, :, i, :] += S
    return w, P, A, lam_max
