"""Sparse direct solves of the symmetric tangent, and its inertia.

``factorize(K)`` returns an object with ``solve(b)`` and ``negative_pivots``
(the number of negative eigenvalues of K, by Sylvester's law of inertia, read
off the diagonal of an LDL^T-like factorisation; -1 when unknown).

Backends: "superlu" (scipy, always present) in symmetric mode -- a fill-reducing
ordering of K + K^T and diagonal pivoting, so U's diagonal is D of K = L D L^T --
and "pardiso" (MKL via the optional ``pypardiso`` package, extra ``fast``), which
reuses the symbolic factorisation across Newton iterations. The default picks
pardiso when it is installed; benchmarks/RESULTS.md compares them.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


class SuperLUFactor:
    def __init__(self, K: sp.csr_matrix) -> None:
        self._lu = spla.splu(K.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                             options={"SymmetricMode": True})
        d = self._lu.U.diagonal()
        self.negative_pivots = int(np.count_nonzero(d < 0))
        if not np.all(np.isfinite(d)) or np.any(d == 0):
            raise np.linalg.LinAlgError("singular tangent")

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._lu.solve(b)


class PardisoFactor:
    """MKL PARDISO, real non-symmetric mode on the full matrix (robust for the
    indefinite tangents past a limit point); inertia is not reported by pypardiso."""

    _solver = None

    def __init__(self, K: sp.csr_matrix) -> None:
        import pypardiso

        if PardisoFactor._solver is None:
            PardisoFactor._solver = pypardiso.PyPardisoSolver()
        self._ps = PardisoFactor._solver
        self._K = K
        self._ps.factorize(K)
        self.negative_pivots = -1

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._ps.solve(self._K, b)


def available_backends() -> list[str]:
    names = ["superlu"]
    try:
        import pypardiso  # noqa: F401
        names.append("pardiso")
    except ImportError:
        pass
    return names


def factorize(K: sp.csr_matrix, backend: str = "superlu"):
    if backend == "pardiso":
        return PardisoFactor(K)
    return SuperLUFactor(K)
