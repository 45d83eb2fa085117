"""Many outputs over one input set: one GP per output, or one per principal component.

Rows of Y (n designs x c outputs) are standardised per column, decomposed by SVD, and
the leading m component scores are each interpolated over the inputs by a GP
(``surrogate.emulator.gp``). m is the smallest count whose reconstruction error on the
training rows is below ``tolerance`` (in output units) everywhere; the variance left in
the dropped components is kept per column and added to the predictive variance.

    vgp = fit_vector_gp(U, Y)
    mean, var = vgp.predict(u)        # (c,), (c,) for one input row
    loo_mean, loo_var = vgp.loo()     # (n, c) leave-one-out, per training row

``fit_output_gps`` is the same object with the identity for components: one GP per
output column, each with its own length scales (the emulator's curves: on the shipped
database's reversed pair, 5-fold cross-validated, the per-curve angle RMSE median fell
from 1.70 deg with 20 principal components of the joint pressure-and-volume vector to
0.86 deg; benchmarks/RESULTS.md). Principal components tie every node to a few shared
length scales, while the low-angle stiffness and the high-angle plateau of a curve depend
on the design's lengths differently. Its ``shared`` columns share one kernel instead
(``gp.fit_shared_gps``: one set of length scales and nugget for all, each column its own
signal variance and mean), so that a query's variance of all of them is one product over
the database: the emulator's 32 pressure nodes since 2026-12-04 (``build.fit_curve_gps``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_solve
from scipy.linalg.blas import stpmv
from scipy.linalg.lapack import dtrtri

from surrogate.emulator.gp import (
    GaussianProcess,
    basis,
    fit_gp,
    fit_shared_gps,
    from_hyperparameters,
    matern52,
    matern52_in_place,
)

MAX_COMPONENTS = 20
# predict_many's rows per block: its kernel temporaries are (outputs, rows, designs), 15 MB
# for 64 outputs of a 450-design group, and stay in cache.
CHUNK_ROWS = 64
MEANS_ONLY = np.array([], dtype=int)    # variance_of for the means alone
# Up to this many training designs a query's L^-1 k for all its outputs is one batched
# product (the force GPs: 37-51 designs); above, one packed BLAS product per output.
SMALL_N = 96
WARM_STARTS = 2              # per-output GPs after the first: the neighbour's optimum + one


@dataclass(frozen=True)
class VectorGP:
    center: np.ndarray          # (c,) column means
    scale: np.ndarray           # (c,) column standard deviations (1 where constant)
    components: np.ndarray      # (m, c) orthonormal rows, standardised units
    gps: tuple[GaussianProcess, ...]
    residual_var: np.ndarray    # (c,) variance of the dropped components, output units

    def __post_init__(self) -> None:
        # Stacked per-component arrays: one query is a few small matrix products
        # (no triangular solves). L^-1 is kept per kernel in double precision,
        # transposed and C-contiguous (``_linv_t``), for the batched product of
        # predict_many; a single query reads the outputs it needs packed in single
        # precision (``_variance_stack``, ``_shifted_variance``). Both are made on a
        # kernel's first variance, not at loading: the shipped emulator's means-only
        # kernels never need them (loading 1.4 s faster; 0.2-0.3 GB never made).
        x = self.gps[0].x
        # outputs that share a kernel (fit_shared_gps) share K and what is made of it,
        # kept once per kernel: "kernel" is each output's kernel, "rep" each kernel's
        # first output (its correlations k, length scales and nugget)
        first: dict[bytes, int] = {}
        kernel = np.array([first.setdefault(gp.lengths.tobytes()
                                            + np.float64(gp.nugget).tobytes(), len(first))
                           for gp in self.gps])
        rep = np.array([int(np.flatnonzero(kernel == q)[0]) for q in range(len(first))])
        inv_l2 = np.array([1.0 / gp.lengths**2 for gp in self.gps])             # (m, d)
        alpha = np.array([gp.alpha for gp in self.gps])                         # (m, n)
        outputs_of = [np.flatnonzero(kernel == q) for q in range(len(rep))]
        stack = {
            "inv_l2": inv_l2, "alpha": alpha,
            # per kernel, gathered once (a query read them by fancy indexing: copies)
            "inv_l2_rep": np.ascontiguousarray(inv_l2[rep]),                    # (K, d)
            "alpha_of": tuple(np.ascontiguousarray(alpha[c]) for c in outputs_of),
            "linv_t": {},                                  # kernel -> (n, n), on first use
            "gram": {},                        # kernel -> K (n, n) above SMALL_N, likewise
            "kinv_h": np.array([_kinv_h(self.gps[i]) for i in rep]),            # (K, n, p)
            "a_inv": np.array([_a_inv(self.gps[i]) for i in rep]),              # (K, p, p)
            "kernel": kernel, "rep": rep,                                       # (m,), (K,)
            "outputs_of": outputs_of,
            "beta": np.array([gp.beta for gp in self.gps]),                     # (m, p)
            "s2": np.array([gp.signal_var for gp in self.gps]),
            "nugget": np.array([gp.nugget for gp in self.gps]),
            "varying": self.gps[0].varying, "x": x,
            "identity": self.components.shape[0] == self.components.shape[1]
            and bool(np.array_equal(self.components, np.eye(len(self.components))))}
        object.__setattr__(self, "_stack", stack)

    def kernels(self, sel: slice | np.ndarray) -> int:
        """How many distinct kernels the outputs ``sel`` have (one product each in a
        query's variance)."""
        return int(np.unique(self._stack["kernel"][sel]).size)  # type: ignore[attr-defined]

    @property
    def per_output(self) -> bool:
        """One GP per output (``fit_output_gps``): the components are the identity."""
        return bool(self._stack["identity"])  # type: ignore[attr-defined]

    def kernel_rows(self, u: np.ndarray) -> np.ndarray:
        """The correlations (K, n) of one input row ``u`` with the training inputs, one
        row per distinct kernel (unit signal variance, no nugget)."""
        st = self._stack  # type: ignore[attr-defined]
        d2 = (st["x"] - np.asarray(u, float).ravel()) ** 2       # (n, d)
        return matern52_in_place(st["inv_l2_rep"] @ d2.T, nonnegative=True)

    def predict(self, u: np.ndarray, variance_of: slice | np.ndarray | None = None,
                rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Mean and variance of every output at one input row ``u``. With one GP per
        output (identity components), ``variance_of`` (a slice or an index array) limits
        the variance, the costly part of a query, to those outputs (NaN for the others); an
        empty index array asks for the means only (any GP). ``rows``: ``kernel_rows(u)``
        when the caller has them already."""
        st = self._stack  # type: ignore[attr-defined]
        u = np.asarray(u, float).ravel()
        k = self.kernel_rows(u) if rows is None else rows        # (K, n): one per kernel
        h = np.concatenate(([1.0], u[st["varying"]]))            # (p,)
        means = st["beta"] @ h + _kernel_dot(k, st)
        # the identity's product changes no number (x 1 + 0s): skipped, as below
        mean = self.center + self.scale * (means if st["identity"] else means @ self.components)
        sel = slice(None) if variance_of is None else variance_of
        if variance_of is not None and _asks_none(variance_of, len(mean)):
            return mean, np.full(len(mean), np.nan)              # the means only
        if variance_of is not None and not self.per_output:
            raise ValueError("variance_of needs one GP per output (identity components)")
        rows, kernels, inverse, linv, kinv_h, a_inv, s2, scale2, residual = \
            self._variance_stack(sel)
        outs = st["rep"][kernels]       # one product per distinct kernel, not per output
        ks = k[kernels]
        if ks.shape[1] <= SMALL_N:      # one batched product beats a BLAS call per output
            v = np.matmul(ks[:, None, :], linv)[:, 0, :]        # linv: (K, n, n)
            left = 1.0 - (v * v).sum(1)
        else:
            left = _shifted_variance(ks, st["nugget"][outs], *linv)   # packed, float32
        rr = h[None, :] - np.matmul(ks[:, None, :], kinv_h)[:, 0, :]
        shared = np.maximum(left + np.einsum("mp,mpq,mq->m", rr, a_inv, rr), 0.0)
        variances = s2 * shared[inverse]
        if variance_of is None:
            var = scale2 * (variances if st["identity"] else variances @ self.components**2
                            ) + residual
        else:
            var = np.full(len(mean), np.nan)
            var[sel] = scale2 * variances + residual
        return mean, var

    def _linv_t(self, q: int) -> np.ndarray:
        """(L^-1)^T of kernel ``q``, C-contiguous (n, n): made on first use and kept (two
        threads may both make it; either result is the same)."""
        st = self._stack  # type: ignore[attr-defined]
        found = st["linv_t"].get(int(q))
        if found is None:
            found = np.ascontiguousarray(_linv(self.gps[int(st["rep"][q])]).T)
            st["linv_t"][int(q)] = found
        return found

    def _gram(self, q: int) -> np.ndarray:
        """Kernel ``q``'s matrix K = C + g I over the training inputs (n, n), made on first
        use and kept (``_shifted_variance`` reads its row K e_i: 40 us of a query on a
        551-design group otherwise; 2.4 MB)."""
        st = self._stack  # type: ignore[attr-defined]
        found = st["gram"].get(int(q))
        if found is None:
            gp = self.gps[int(st["rep"][q])]
            found = matern52(gp.x, gp.x, gp.lengths)
            found[np.diag_indices_from(found)] += gp.nugget
            st["gram"][int(q)] = found
        return found

    def _variance_stack(self, sel: slice | np.ndarray) -> tuple:
        """The arrays a variance over outputs ``sel`` reads: their indices, the distinct
        kernels among them and each output's place among those, per kernel L^-1 packed in
        single precision (its lower triangle row by row, n (n + 1) / 2 numbers: BLAS stpmv
        reads exactly that) and K (``_shifted_variance`` reads both; up to SMALL_N designs
        instead the (K, n, n) stack of (L^-1)^T in double precision, for one batched
        product), K^-1 H and A^-1, the outputs' signal variances, and their squared scales
        and residual variances (all outputs' with ``sel`` all: ``predict``'s two forms);
        gathered once per distinct ``sel`` (a query asks for the same few)."""
        st = self._stack  # type: ignore[attr-defined]
        rows = np.arange(len(st["s2"]))[sel]
        key = rows.tobytes()
        cache = st.setdefault("variance_stacks", {})
        hit = cache.get(key)
        if hit is None:
            lower = np.tril_indices(len(st["x"]))
            kernels, inverse = np.unique(st["kernel"][rows], return_inverse=True)
            linv = (np.array([self._linv_t(q) for q in kernels])
                    if len(st["x"]) <= SMALL_N else
                    (tuple(self._gram(q) for q in kernels),
                     tuple(np.ascontiguousarray(self._linv_t(q).T)[lower]
                           .astype(np.float32) for q in kernels)))
            hit = (rows, kernels, inverse.ravel(), linv,
                   np.ascontiguousarray(st["kinv_h"][kernels]),
                   np.ascontiguousarray(st["a_inv"][kernels]), st["s2"][rows].copy(),
                   *((self.scale**2, self.residual_var) if isinstance(sel, slice)
                     and sel == slice(None) else (self.scale[sel] ** 2,
                                                  self.residual_var[sel])))
            if len(cache) < 8:
                cache[key] = hit
        return hit

    def predict_many(self, u: np.ndarray, variance_of: slice | np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
        """Means and variances (N, c) at the N rows of ``u``. As in ``predict``, with one GP
        per output ``variance_of`` limits the variance (N n^2 per output, the costly part)
        to those outputs, NaN for the others; an empty index array asks for means only."""
        st = self._stack  # type: ignore[attr-defined]
        u = np.atleast_2d(np.asarray(u, float))
        if len(u) > CHUNK_ROWS:     # bounded temporaries: (m, CHUNK_ROWS, n) at most
            parts = [self.predict_many(u[i:i + CHUNK_ROWS], variance_of)
                     for i in range(0, len(u), CHUNK_ROWS)]
            return (np.concatenate([m for m, _ in parts]),
                    np.concatenate([v for _, v in parts]))
        n_rows, (n, d) = len(u), st["x"].shape
        d2 = (u.T[:, :, None] - st["x"].T[:, None, :]) ** 2             # (d, N, n)
        r2 = (st["inv_l2_rep"] @ d2.reshape(d, -1)).reshape(-1, n_rows, n)
        k = matern52_in_place(r2, nonnegative=True)           # (K, N, n): one per kernel
        h = np.column_stack((np.ones(len(u)), u[:, st["varying"]]))     # (N, p)
        means = h @ st["beta"].T
        for q, (cols, alpha) in enumerate(zip(st["outputs_of"], st["alpha_of"], strict=True)):
            means[:, cols] += k[q] @ alpha.T
        mean = self.center + self.scale * (means @ self.components)
        rows = np.arange(len(st["s2"]))[slice(None) if variance_of is None else variance_of]
        if variance_of is not None and len(rows) and not self.per_output:
            raise ValueError("variance_of needs one GP per output (identity components)")
        variances = np.empty((len(rows), len(u)))
        shared: dict[int, np.ndarray] = {}   # per kernel: outputs sharing it share this
        for i, j in enumerate(rows):      # one GEMM per kernel: no copy of L^-1
            q = int(st["kernel"][j])
            if q not in shared:
                kq = k[q]
                v = kq @ self._linv_t(q)                                 # (L^-1 k)^T
                rr = h - kq @ st["kinv_h"][q]
                quad = np.einsum("Np,pq,Nq->N", rr, st["a_inv"][q], rr)
                shared[q] = np.maximum(1.0 - (v * v).sum(1) + quad, 0.0)
            variances[i] = st["s2"][j] * shared[q]
        if variance_of is None:
            var = self.scale**2 * (variances.T @ self.components**2) + self.residual_var
        else:
            var = np.full(mean.shape, np.nan)
            var[:, rows] = self.scale[rows] ** 2 * variances.T + self.residual_var[rows]
        return mean, var

    def loo(self) -> tuple[np.ndarray, np.ndarray]:
        """Leave-one-out mean and variance of every output at every training row."""
        n = len(self.gps[0].y)
        scores = np.empty((n, len(self.gps)))
        variances = np.empty((n, len(self.gps)))
        for j, gp in enumerate(self.gps):
            r, v = gp.loo()
            scores[:, j] = gp.y - r
            variances[:, j] = v
        mean = self.center + self.scale * (scores @ self.components)
        var = self.scale**2 * (variances @ self.components**2) + self.residual_var
        return mean, var

    def as_dict(self) -> dict[str, object]:
        return {"center": self.center.tolist(), "scale": self.scale.tolist(),
                "components": self.components.tolist(),
                "residual_var": self.residual_var.tolist(),
                "gps": [gp.as_dict() for gp in self.gps]}


def _asks_none(variance_of: slice | np.ndarray, outputs: int) -> bool:
    """Whether ``variance_of`` selects no output of ``outputs`` (the means only): an empty
    index array (MEANS_ONLY) read without making the outputs' indices (a mask: made)."""
    if isinstance(variance_of, np.ndarray) and variance_of.dtype != bool:
        return variance_of.size == 0
    return len(np.arange(outputs)[variance_of]) == 0


def _kernel_dot(k: np.ndarray, st: dict) -> np.ndarray:
    """k_q(output) . alpha_output for every output (m,), from the correlations ``k``
    (K, n) of the distinct kernels: one product per kernel."""
    if len(k) == len(st["kernel"]):         # a kernel per output, in output order
        return np.einsum("mn,mn->m", st["alpha"], k)
    out = np.empty(len(st["kernel"]))
    for q, (cols, alpha) in enumerate(zip(st["outputs_of"], st["alpha_of"], strict=True)):
        out[cols] = alpha @ k[q]
    return out


def _shifted_variance(ks: np.ndarray, nugget: np.ndarray, grams: tuple[np.ndarray, ...],
                      packed_linv: tuple[np.ndarray, ...]) -> np.ndarray:
    """1 - k^T K^-1 k for each kernel's correlations ``ks`` (m, n) with the training
    inputs, K = L L^T = C + g I (unit signal variance, nugget g; ``grams``), from L^-1
    packed in single precision (``packed_linv``).

    For any training row i, K^-1 k = e_i + K^-1 delta with delta = k - K e_i, so

        1 - k^T K^-1 k = 2 (1 - k_i) + g - |L^-1 delta|^2      (K_ii = 1 + g).

    With i the training design most correlated with the query, delta is small near the
    data and so is the single-precision error of |L^-1 delta|^2; the direct form
    1 - |L^-1 k|^2 cancels two numbers near 1 there, and in single precision it lost the
    variance (held-out band coverage 0.91 -> 0.79). On the shipped emulator's four groups,
    300 queries each (random, and 0.001 and 0.03 from database designs), this variance is
    within 5 % of the double-precision one (median 0.1 %), at 0.6 of the time
    (benchmarks/RESULTS.md, fifteenth session)."""
    n = ks.shape[1]
    i = int(np.argmax(ks[0] if len(ks) == 1 else ks.sum(0)))     # one row for all kernels
    if len(ks) == 1:    # one kernel (a query's usual): the same numbers without the lists
        delta = (ks[0] - grams[0][i]).astype(np.float32)
        v = stpmv(n, packed_linv[0], delta, lower=0, trans=1).astype(float)[None, :]
    else:
        delta = np.array([k - gram[i] for k, gram in zip(ks, grams, strict=True)],
                         dtype=np.float32)                             # k - K e_i
        v = np.array([stpmv(n, ap, dj, lower=0, trans=1)               # L^-1 delta
                      for ap, dj in zip(packed_linv, delta, strict=True)], dtype=float)
    return 2.0 * (1.0 - ks[:, i]) + nugget - (v * v).sum(1)


def _linv(gp: GaussianProcess) -> np.ndarray:
    """L^-1 of the kernel's Cholesky factor, by LAPACK's triangular inverse (dtrtri: half
    the time of solving against the identity, 1e-14 apart on a 450-design kernel)."""
    inverse, info = dtrtri(gp.chol, lower=1)
    if info != 0:       # a singular factor: cannot come from a successful Cholesky
        raise np.linalg.LinAlgError(f"triangular inverse failed (dtrtri info {info})")
    return np.tril(inverse)


def _kinv_h(gp: GaussianProcess) -> np.ndarray:
    return cho_solve((gp.chol, True), basis(gp.x, gp.varying))


def _a_inv(gp: GaussianProcess) -> np.ndarray:
    return cho_solve((gp.hk_chol, True), np.eye(gp.hk_chol.shape[0]))


def vector_gp_from_dict(d: dict) -> VectorGP:
    """Rebuild from ``as_dict`` (the factorisations are recomputed, not stored)."""
    factors: dict[bytes, np.ndarray] = {}     # outputs sharing a kernel: one Cholesky
    gps_: list[GaussianProcess] = []
    for g in d["gps"]:
        x, lengths, nugget = (np.array(g["x"], float), np.array(g["lengths"], float),
                              float(g["nugget"]))
        key = x.tobytes() + lengths.tobytes() + np.float64(nugget).tobytes()
        gp = from_hyperparameters(x, np.array(g["y"], float), lengths, nugget,
                                  factors.get(key))
        factors.setdefault(key, gp.chol)
        gps_.append(gp)
    gps = tuple(gps_)
    return VectorGP(np.array(d["center"], float), np.array(d["scale"], float),
                    np.array(d["components"], float), gps,
                    np.array(d["residual_var"], float))


def _standardised(y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Column means, standard deviations (1 where constant) and the standardised
    outputs of complete rows ``y`` (n, c)."""
    y = np.asarray(y, float)
    if not np.isfinite(y).all():
        raise ValueError("outputs must be complete (no NaN)")
    center = y.mean(0)
    scale = y.std(0)
    scale = np.where(scale > 1e-12, scale, 1.0)
    return center, scale, (y - center) / scale


def fit_output_gps(u: np.ndarray, y: np.ndarray, seed: int = 0,
                   shared: slice | None = None) -> VectorGP:
    """One GP per (standardised) output column of ``y`` (n, c) over inputs ``u`` (n, d):
    a VectorGP whose components are the identity, with no truncation variance. The
    columns of ``shared`` share one kernel (``gp.fit_shared_gps``: a query's variance of
    all of them is one product); the others have their own."""
    u = np.asarray(u, float)
    center, scale, z = _standardised(y)
    cols = np.arange(z.shape[1])
    tied = cols[shared] if shared is not None else cols[:0]
    gps: list[GaussianProcess | None] = [None] * z.shape[1]
    if tied.size:
        for j, gp in zip(tied, fit_shared_gps(u, z[:, tied], seed=seed), strict=True):
            gps[j] = gp
    warm = None
    for j in np.setdiff1d(cols, tied):
        # neighbouring nodes of a curve have nearly the same length scales: start from
        # the previous node's optimum (and once from the default), not 4 cold starts
        gps[j] = warm = (fit_gp(u, z[:, j], seed=seed + j) if warm is None else
                         fit_gp(u, z[:, j], starts=WARM_STARTS, seed=seed + j, warm=warm))
    return VectorGP(center, scale, np.eye(z.shape[1]), tuple(gps), np.zeros(z.shape[1]))


def fit_vector_gp(u: np.ndarray, y: np.ndarray, tolerance: float = 1e-3,
                  seed: int = 0, max_components: int = MAX_COMPONENTS) -> VectorGP:
    """Fit to inputs ``u`` (n, d) and complete outputs ``y`` (n, c), with at most
    ``max_components`` principal components (the rest is kept as variance)."""
    u = np.asarray(u, float)
    center, scale, z = _standardised(y)
    _, sv, vt = np.linalg.svd(z, full_matrices=False)
    m = 1
    while m < min(max_components, len(sv)):
        recon = (z @ vt[:m].T) @ vt[:m]
        if np.max(np.abs(recon - z) * scale) < tolerance:
            break
        m += 1
    comps = vt[:m]
    scores = z @ comps.T
    recon = scores @ comps
    residual_var = ((z - recon) * scale).var(0) + ((z - recon) * scale).mean(0) ** 2
    gps = tuple(fit_gp(u, scores[:, j], seed=seed + j) for j in range(m))
    return VectorGP(center, scale, comps, gps, residual_var)
