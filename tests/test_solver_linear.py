"""Sparse direct solves of the tangent: every backend gives the same solution and the
same inertia (number of negative eigenvalues, checked against a dense eigen-solve)."""

import numpy as np
import pytest
import scipy.sparse as sp

from solver.linear import available_backends, factorize


def _indefinite(n=60, negative=3, seed=0):
    """A sparse symmetric matrix with a known number of negative eigenvalues."""
    rng = np.random.default_rng(seed)
    A = sp.random(n, n, density=0.08, random_state=seed) + sp.eye(n)
    A = (A + A.T).toarray()
    w, V = np.linalg.eigh(A)
    w = np.abs(w) + 0.5
    w[:negative] *= -1.0
    B = V @ np.diag(w) @ V.T
    B[np.abs(B) < 0.05] = 0.0                 # sparsify, keep symmetry
    B = 0.5 * (B + B.T)
    return sp.csr_matrix(B), int((np.linalg.eigvalsh(B) < 0).sum()), rng.standard_normal(n)


@pytest.mark.parametrize("backend", available_backends())
def test_solution_and_inertia(backend):
    K, negative, b = _indefinite()
    assert negative > 0
    fac = factorize(K, backend)
    x = fac.solve(b)
    assert np.abs(K @ x - b).max() < 1e-10 * np.abs(b).max()
    assert fac.negative_pivots == negative
    B = np.column_stack((b, 2.0 * b + 1.0))            # several right-hand sides at once
    X = fac.solve(B)
    assert X.shape == B.shape
    assert np.abs(K @ X - B).max() < 1e-10 * np.abs(B).max()


@pytest.mark.skipif("pardiso" not in available_backends(), reason="pypardiso not installed")
def test_pardiso_reuses_its_analysis_and_follows_a_new_pattern():
    K, _, b = _indefinite(seed=1)
    x1 = factorize(K, "pardiso").solve(b)
    K2 = K.copy()
    K2.data *= 2.0                            # same pattern, new values
    assert np.allclose(factorize(K2, "pardiso").solve(b), 0.5 * x1, rtol=1e-10, atol=1e-12)
    K3, _, b3 = _indefinite(n=40, seed=2)     # another pattern
    x3 = factorize(K3, "pardiso").solve(b3)
    assert np.abs(K3 @ x3 - b3).max() < 1e-10 * np.abs(b3).max()


def test_unknown_backend_is_refused():
    K, _, _ = _indefinite()
    with pytest.raises(ValueError, match="auto | superlu | pardiso"):
        factorize(K, "cholmod")


@pytest.mark.skipif("pardiso" not in available_backends(), reason="pypardiso not installed")
def test_pardiso_falls_back_to_pivoting_where_a_diagonal_pivot_vanishes():
    """Saddle blocks [[0, 1], [1, 0]] (eigenvalues +-1): 1 x 1 diagonal pivoting meets a
    zero pivot, so the factorisation is repeated with Bunch-Kaufman pivoting."""
    n = 20
    A = sp.lil_matrix((n, n))
    for i in range(0, 10, 2):
        A[i, i + 1] = A[i + 1, i] = 1.0
    for i in range(10, n):
        A[i, i] = 2.0
    A[0, 12] = A[12, 0] = 0.3
    A = A.tocsr()
    b = np.arange(1.0, n + 1.0)
    fac = factorize(A, "pardiso")
    assert fac.careful
    assert fac.negative_pivots == int((np.linalg.eigvalsh(A.toarray()) < 0).sum()) == 5
    assert np.abs(A @ fac.solve(b) - b).max() < 1e-12 * np.abs(b).max()
