"""Stability of a converged state under pressure control and under volume control.

Equilibrium is a stationary point of the potential Pi(u) = E(u) - p (V(u) - V_t). Its
second variation is the tangent K = E'' - p V'' (solver/discrete.py).

* Pressure control (p prescribed): stable when K is positive definite; the number of
  negative eigenvalues of K (its inertia, counted by the factorisation) is the index.
* Volume control (the syringe pump, V prescribed): only variations that keep the volume,
  g . du = 0 with g = dV/du, count. By Haynsworth's inertia additivity applied to the
  bordered matrix [[K, g], [g^T, 0]], the index on that subspace is

      index_V = index(K) - (1 if g^T K^-1 g < 0 else 0).

  Along the volume-controlled path dV/dp = g^T K^-1 g, so a negative value means the
  pressure is falling (past a pressure maximum): that one negative eigenvalue of K is
  the limit point's, harmless under volume control. Any further negative eigenvalue
  belongs to a mode that changes the shape at constant volume: a bifurcation (e.g. one
  lobe of the membrane grows while another deflates, the paper's "two balloons").

Where index_V first rises above 0, ``constrained_modes`` finds the volume-neutral
unstable modes (eigenpairs of K restricted to g-orthogonal displacements nearest 0,
by shift-invert Lanczos through the factorised bordered system), and the stepping
injects the first one to leave the unstable branch (solver/stepping.py).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla


def volume_control_index(negative_pivots: int, g_kinv_g: float) -> int:
    """Number of unstable volume-neutral modes (see the module docstring); -1 if the
    inertia is unknown."""
    if negative_pivots < 0 or not np.isfinite(g_kinv_g):
        return -1
    return max(0, negative_pivots - (1 if g_kinv_g < 0 else 0))


def classify(negative_pivots: int, g_kinv_g: float, volume_control: bool) -> str:
    """'stable', 'limit point passed' (unstable only under pressure control), or
    'bifurcation' (unstable under the step's own control)."""
    if negative_pivots <= 0:
        return "stable"
    index = volume_control_index(negative_pivots, g_kinv_g) if volume_control else (
        negative_pivots)
    return "bifurcation" if index > 0 else "limit point passed"


def constrained_modes(K, g: np.ndarray, factor, k: int = 1
                      ) -> tuple[np.ndarray, np.ndarray]:
    """The k eigenpairs nearest 0 of K on the subspace g . x = 0 (volume-neutral), as
    (eigenvalues (k,), unit eigenvectors (n, k)); ``factor`` is K's factorisation
    (solver.linear.factorize). The inverse on the subspace is the bordered solve

        x = K^-1 y - K^-1 g (g^T K^-1 y) / (g^T K^-1 g)
    """
    n = K.shape[0]
    kg = factor.solve(g)
    gkg = float(g @ kg)
    gn = g / np.linalg.norm(g)

    def project(x: np.ndarray) -> np.ndarray:
        return x - gn * float(gn @ x)

    def op(x: np.ndarray) -> np.ndarray:
        px = project(np.ravel(x))
        return project(K @ px)

    def op_inv(y: np.ndarray) -> np.ndarray:
        y = project(np.ravel(y))
        ky = factor.solve(y)
        return project(ky - kg * float(g @ ky) / gkg)

    A = spla.LinearOperator((n, n), matvec=op, dtype=float)
    Ainv = spla.LinearOperator((n, n), matvec=op_inv, dtype=float)
    v0 = project(np.random.default_rng(0).standard_normal(n))
    vals, vecs = spla.eigsh(A, k=k, sigma=0.0, OPinv=Ainv, which="LM", v0=v0,
                            tol=1e-8, maxiter=2000)
    order = np.argsort(vals)
    vecs = vecs[:, order]
    return vals[order], vecs / np.linalg.norm(vecs, axis=0)
