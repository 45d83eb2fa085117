"""Sparse direct solves of the symmetric tangent, and its inertia.

``factorize(K)`` returns an object with ``solve(b)`` and ``negative_pivots``
(the number of negative eigenvalues of K, by Sylvester's law of inertia, read
off the diagonal of an LDL^T-like factorisation; -1 when unknown).

Backends: "superlu" (scipy, always present) in symmetric mode -- a fill-reducing
ordering of K + K^T and diagonal pivoting, so U's diagonal is D of K = L D L^T --
and "pardiso" (MKL PARDISO via ``pypardiso``, installed by default on x86_64),
symmetric indefinite on the upper triangle, which reuses the ordering and symbolic
factorisation across Newton iterations: ~4x faster than SuperLU on the default
mesh. "auto" (the default) picks pardiso when it is installed;
benchmarks/RESULTS.md compares them.
"""

from __future__ import annotations

import functools
import glob
import os
import sys

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


def _import_pypardiso():
    """Import pypardiso, pointing it at the MKL runtime installed beside this Python.

    pypardiso looks for ``mkl_rt`` with ``ctypes.util.find_library`` and, failing that
    (a pip-installed MKL is not on the loader's path), with a recursive glob over
    ``sys.prefix``: ~1 s of CPU time at its import and again for every solver handle,
    i.e. for every curve (benchmarks/RESULTS.md, issue 12, third session). Its own
    variable ``PYPARDISO_MKL_RT`` skips the search; it is set here, when unset, to the
    library in ``sys.prefix/lib`` where pip puts it.
    """
    # MKL's OpenMP threads spin for 200 ms after each parallel region by default: after a
    # factorisation the spinning worker takes the second core from the assembly's helper
    # thread (solver/parallel.py), ~2 s of CPU per curve. Sleep at once instead (read when
    # MKL's OpenMP runtime starts, i.e. before its first call; a user's setting wins).
    os.environ.setdefault("KMP_BLOCKTIME", "0")
    if "PYPARDISO_MKL_RT" not in os.environ:
        found = sorted(glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*")), key=len)
        if found:
            os.environ["PYPARDISO_MKL_RT"] = found[0]
    import pypardiso

    return pypardiso


# PARDISO's iparm (0-based): inputs, and outputs of the numerical factorisation.
IPARM_REFINEMENT = 7       # maximum iterative-refinement steps per solve
IPARM_PIVOTING = 20        # 0: 1 x 1 diagonal pivoting; 1: Bunch-Kaufman 1 x 1 and 2 x 2
IPARM_PERTURBED = 13       # pivots perturbed (replaced by +-1e-8 ||A||)
IPARM_NEGATIVE = 22        # negative eigenvalues (inertia)


class _PardisoPattern:
    """An MKL PARDISO handle analysed (ordering, symbolic factorisation) for one
    sparsity pattern, in symmetric-indefinite mode on the upper triangle."""

    def __init__(self, K: sp.csr_matrix) -> None:
        pypardiso = _import_pypardiso()
        self.ps = pypardiso.PyPardisoSolver(mtype=-2)       # real symmetric indefinite
        self.indptr, self.indices = K.indptr, K.indices
        rows = np.repeat(np.arange(K.shape[0], dtype=np.int32), np.diff(K.indptr))
        self.upper = np.flatnonzero(K.indices >= rows)      # CSR order is kept
        counts = np.bincount(rows[self.upper], minlength=K.shape[0])
        del rows                                 # the analysis below is the solve's peak
        U = sp.csr_matrix((K.data[self.upper], K.indices[self.upper],
                           np.concatenate(([0], np.cumsum(counts)))), shape=K.shape)
        U.sort_indices()
        self.U = U
        self._call(11, np.zeros(K.shape[0]))     # PARDISO's defaults fill iparm here
        self.defaults = self.ps.iparm.copy()

    def configure(self, careful: bool) -> None:
        """``careful=False``: 1 x 1 diagonal pivoting and no iterative refinement;
        ``careful=True``: PARDISO's defaults for symmetric indefinite matrices
        (Bunch-Kaufman 1 x 1 and 2 x 2 pivoting, two refinement steps per solve)."""
        self.ps.iparm[:] = self.defaults
        if not careful:
            self.ps.iparm[IPARM_PIVOTING] = 0
            self.ps.iparm[IPARM_REFINEMENT] = 0

    def matches(self, K: sp.csr_matrix) -> bool:
        return (_same_memory(K.indptr, self.indptr) and _same_memory(K.indices, self.indices)
                ) or (K.shape == self.U.shape and np.array_equal(K.indptr, self.indptr)
                      and np.array_equal(K.indices, self.indices))

    def _call(self, phase: int, b: np.ndarray) -> np.ndarray:
        self.ps.set_phase(phase)
        return self.ps._call_pardiso(self.U, b)

    def release(self) -> None:
        self.ps.set_phase(-1)
        self.ps._call_pardiso(sp.csr_matrix((0, 0)), np.zeros(0))


def _same_memory(a: np.ndarray, b: np.ndarray) -> bool:
    """The same array memory (scipy hands out a new view of the pattern's index arrays
    with every matrix; the analysed pattern keeps its own alive, so its address is not
    reused by another array)."""
    return (a is b) or (a.ctypes.data == b.ctypes.data and a.shape == b.shape
                        and a.strides == b.strides and a.dtype == b.dtype)


class PardisoFactor:
    """MKL PARDISO (optional ``pypardiso``), symmetric indefinite. The ordering and the
    symbolic factorisation are computed once per sparsity pattern and reused by
    every Newton iteration; only the numerical factorisation is repeated. Inertia
    from PARDISO's own count of negative eigenvalues.

    L D L^T with 1 x 1 diagonal pivots and solves without iterative refinement: on
    our tangents ~30 % cheaper factorisations and 3x cheaper solves than PARDISO's
    defaults, with the same residual (~1e-12) and inertia, also when K is strongly
    indefinite. Should a pivot need perturbing (then the solve is inexact), the
    factorisation is repeated with the defaults: Bunch-Kaufman 1 x 1 and 2 x 2 pivots
    and two refinement steps per solve (``careful``)."""

    _pattern: _PardisoPattern | None = None     # one analysed pattern per process

    def __init__(self, K: sp.csr_matrix) -> None:
        from pypardiso.pardiso_wrapper import PyPardisoError

        cached = PardisoFactor._pattern
        if cached is None or not cached.matches(K):
            if cached is not None:
                cached.release()
            cached = PardisoFactor._pattern = _PardisoPattern(K)
        self._p = cached
        np.take(K.data, cached.upper, out=cached.U.data, mode="clip")   # unbuffered
        # Diagonal pivoting first; a factorisation that had to perturb a pivot is
        # repeated with PARDISO's defaults (benchmarks/RESULTS.md, issue 12, fifth session).
        for careful in (False, True):
            cached.configure(careful)
            try:
                self._p._call(22, np.zeros(K.shape[0]))
            except PyPardisoError as exc:
                if careful:
                    raise np.linalg.LinAlgError(f"PARDISO factorisation failed: {exc}") from None
                continue
            if cached.ps.iparm[IPARM_PERTURBED] == 0:
                break
        self.careful = careful
        self.negative_pivots = int(cached.ps.iparm[IPARM_NEGATIVE])

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve for one right-hand side (n,) or several (n, k) in one pass."""
        self._p.configure(self.careful)
        x = self._p._call(33, np.asfortranarray(b, dtype=float))
        if not np.all(np.isfinite(x)):
            raise np.linalg.LinAlgError("PARDISO returned a non-finite solution")
        return np.ascontiguousarray(x)


@functools.cache
def _pardiso_installed() -> bool:
    try:
        _import_pypardiso()
    except ImportError:
        return False
    return True


def available_backends() -> list[str]:
    return ["superlu", "pardiso"] if _pardiso_installed() else ["superlu"]


def default_backend() -> str:
    """"pardiso" when pypardiso is installed (x86_64, the default install), else "superlu"."""
    return "pardiso" if "pardiso" in available_backends() else "superlu"


def factorize(K: sp.csr_matrix, backend: str = "auto"):
    """Factorise the symmetric tangent with ``backend`` ("auto", "superlu", "pardiso")."""
    if backend == "auto":
        backend = default_backend()
    if backend == "pardiso":
        return PardisoFactor(K)
    if backend != "superlu":
        raise ValueError(f"unknown linear-solver backend {backend!r}: auto | superlu | pardiso")
    return SuperLUFactor(K)
