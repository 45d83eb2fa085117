"""Gaussian-process regression with a linear mean (universal kriging), in numpy.

    gp = fit_gp(x, y)                 # x (n, d) in the unit cube, y (n,)
    mean, var = gp.predict(xq)        # var: of the latent function, basis included
    r, v = gp.loo()                   # leave-one-out residuals and variances (closed form)

Kernel: Matern 5/2 with one length scale per input (ARD),

    k(x, x') = s2 (1 + sqrt5 r + 5 r^2 / 3) exp(-sqrt5 r),  r^2 = sum ((x - x') / l)^2

plus a nugget g s2 on the diagonal. The mean is h(x)^T beta with h = (1, x) and beta
integrated out under a flat prior (generalised least squares), so the variance includes
the mean's uncertainty. Hyperparameters (log l, log s2, log g) maximise the restricted
(REML) log likelihood, from several starts with L-BFGS-B.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_solve, solve_triangular
from scipy.linalg.lapack import dpotrf, dpotri
from scipy.optimize import minimize

SQRT5 = np.sqrt(5.0)
NUGGET_BOUNDS = (1e-10, 1e-2)        # relative to the signal variance
LENGTH_BOUNDS = (0.05, 20.0)         # in unit-cube coordinates
INTERPOLATION_SD = 1e-4              # the nugget's largest sd, relative to std(y)


def matern52(xa: np.ndarray, xb: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Matern 5/2 correlation between rows of xa and xb (unit signal variance).

    The scaled squared distance is summed one input at a time into one (na, nb) array:
    no (na, nb, d) temporaries (on a 450 x 450 x 9 kernel 0.25-0.3 of the time of the
    broadcast form, 6e-16 apart; loading the shipped emulator builds ~600 of them)."""
    xa, xb = np.atleast_2d(xa), np.atleast_2d(xb)
    r2 = np.zeros((len(xa), len(xb)))
    for j, length in enumerate(np.asarray(lengths, float)):
        diff = np.subtract.outer(xa[:, j] / length, xb[:, j] / length)
        diff *= diff
        r2 += diff
    return matern52_in_place(r2)


def matern52_in_place(r2: np.ndarray, nonnegative: bool = False) -> np.ndarray:
    """The Matern 5/2 kernel (1 + sqrt5 r + 5 r^2 / 3) exp(-sqrt5 r) from the scaled squared
    distances ``r2``, overwritten (no temporaries but one; ~0.1 of a query's time).
    ``nonnegative``: ``r2`` cannot be below 0 (sums of products of non-negative numbers),
    so the clamp against rounding is skipped (it changes no number there; 8 us of the 32
    volume kernels' rows)."""
    t = np.sqrt(r2 if nonnegative else np.maximum(r2, 0.0, out=r2), out=r2)
    # t = -sqrt5 r: the sign folded into the scaling, one pass fewer and the same numbers
    # (5 r^2 / 3 = t^2 / 3, and adding sqrt5 r is subtracting t, both exactly)
    t *= -SQRT5
    poly = t * t
    poly *= 1.0 / 3.0
    poly -= t
    poly += 1.0
    np.exp(t, out=t)
    poly *= t
    return poly


def basis(x: np.ndarray, varying: np.ndarray | None = None) -> np.ndarray:
    """Mean-function basis h(x) = (1, x_i for the inputs that vary in the training set)."""
    cols = x if varying is None else x[:, varying]
    return np.column_stack((np.ones(len(x)), cols))


def varying_inputs(x: np.ndarray) -> np.ndarray:
    """Mask of the inputs that are not constant over the training rows."""
    return np.ptp(x, axis=0) > 1e-9


@dataclass(frozen=True)
class GaussianProcess:
    """A fitted GP; arrays are what prediction needs (see the module docstring)."""

    x: np.ndarray            # (n, d) training inputs
    y: np.ndarray            # (n,) training outputs
    lengths: np.ndarray      # (d,)
    signal_var: float
    nugget: float            # relative to signal_var
    beta: np.ndarray         # GLS mean coefficients
    alpha: np.ndarray        # K^-1 (y - H beta), K in units of signal_var
    chol: np.ndarray         # lower Cholesky factor of K (correlation + nugget)
    hk_chol: np.ndarray      # lower Cholesky factor of H^T K^-1 H
    varying: np.ndarray      # inputs in the mean's basis (those that vary in x)

    def predict(self, xq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean and variance of the latent function at rows of ``xq``."""
        xq = np.atleast_2d(xq)
        kq = matern52(xq, self.x, self.lengths)                   # (m, n)
        hq = basis(xq, self.varying)
        mean = hq @ self.beta + kq @ self.alpha
        v = solve_triangular(self.chol, kq.T, lower=True)         # (n, m)
        h = basis(self.x, self.varying)
        w = solve_triangular(self.chol, h, lower=True)            # (n, p)
        r = hq.T - w.T @ v                                        # (p, m)
        s = solve_triangular(self.hk_chol, r, lower=True)
        var = 1.0 - (v * v).sum(0) + (s * s).sum(0)
        return mean, self.signal_var * np.maximum(var, 0.0)

    def loo(self) -> tuple[np.ndarray, np.ndarray]:
        """Leave-one-out residuals y_i - mean_{-i}(x_i) and predictive variances (the
        nugget included), exact for fixed hyperparameters (restricted form)."""
        p, d = self.loo_projector()
        return (p @ self.y) / d, self.signal_var / d

    def loo_projector(self) -> tuple[np.ndarray, np.ndarray]:
        """P = K^-1 - K^-1 H (H^T K^-1 H)^-1 H^T K^-1 and its diagonal d: the leave-one-out
        residuals of any outputs y on this kernel are (P y) / d (``loo``)."""
        n = len(self.y)
        h = basis(self.x, self.varying)
        kinv = cho_solve((self.chol, True), np.eye(n))
        kh = kinv @ h
        hk = h.T @ kh
        # the same relative jitter as the fit's (_factor): with few points and long length
        # scales K is near singular and H^T K^-1 H loses its last digits
        hk = hk + 1e-12 * np.trace(hk) / len(hk) * np.eye(len(hk))
        p = kinv - kh @ np.linalg.lstsq(hk, kh.T, rcond=None)[0]
        return p, np.diag(p)

    def as_dict(self) -> dict[str, object]:
        return {"x": self.x.tolist(), "y": self.y.tolist(), "lengths": self.lengths.tolist(),
                "signal_var": self.signal_var, "nugget": self.nugget}


def _factor(x: np.ndarray, y: np.ndarray, lengths: np.ndarray, nugget: float,
            chol: np.ndarray | None = None):
    n = len(y)
    if chol is None:
        chol = np.linalg.cholesky(matern52(x, x, lengths) + nugget * np.eye(n))
    h = basis(x, varying_inputs(x))
    w = solve_triangular(chol, h, lower=True)
    z = solve_triangular(chol, y, lower=True)
    hk = w.T @ w
    # a relative jitter of 1e-12: the mean's normal matrix stays factorable when a fit
    # with few points ends at length scales that make it nearly singular
    hk_chol = np.linalg.cholesky(hk + 1e-12 * np.trace(hk) / len(hk) * np.eye(len(hk)))
    beta = cho_solve((hk_chol, True), w.T @ z)
    resid = z - w @ beta
    return chol, hk_chol, beta, resid


@dataclass(frozen=True)
class TrainingPairs:
    """What the restricted likelihood reads of the training inputs, computed once per fit:
    the squared coordinate differences of every pair of rows i > j (the lower triangle,
    row by row; (d, n (n - 1) / 2)), their indices, and the mean's basis H."""

    rows: np.ndarray         # i of each pair
    cols: np.ndarray         # j of each pair (j < i)
    squares: np.ndarray      # (d, pairs): (x_i - x_j)^2 per coordinate
    h: np.ndarray            # (n, p) basis(x, varying_inputs(x))

    @classmethod
    def of(cls, x: np.ndarray) -> TrainingPairs:
        rows, cols = np.tril_indices(len(x), -1)
        return cls(rows, cols, np.ascontiguousarray(((x[rows] - x[cols]) ** 2).T),
                   basis(x, varying_inputs(x)))


def _neg_reml(params: np.ndarray, x: np.ndarray, y: np.ndarray,
              pairs: TrainingPairs | None = None) -> tuple[float, np.ndarray]:
    """Negative restricted log likelihood (signal variance profiled out) and its
    gradient in (log lengths, log nugget): with P = K^-1 - K^-1 H (H^T K^-1 H)^-1 H^T K^-1
    and a = P y, d(-log L) = 1/2 tr((P - a a^T / s2) dK), s2 = y^T P y / (n - p).

    ``y`` (n,) or (n, m): m outputs sharing the kernel (lengths and nugget), each with its
    own signal variance s2_j and mean coefficients, independent given the kernel: the sum
    of their likelihoods, gradient 1/2 tr((m P - sum_j a_j a_j^T / s2_j) dK).

    K is symmetric with a constant diagonal, so the kernel and the trace of the gradient
    are evaluated on the pairs i > j only (``pairs``: once per fit), K is filled in its
    lower triangle for LAPACK's Cholesky factorisation (dpotrf) and inverted from that
    factor (dpotri, a third of the work of two triangular solves against the identity):
    at n = 450, d = 7 one evaluation takes 0.16x the time of the dense form it replaced,
    to 1e-13 in value and gradient (benchmarks/RESULTS.md)."""
    n, d = x.shape
    ys = y.reshape(n, -1)
    m = ys.shape[1]
    pr = pairs if pairs is not None else TrainingPairs.of(x)
    inv_l2 = np.exp(-2.0 * params[:d])
    nugget = float(np.exp(params[d]))
    r2 = inv_l2 @ pr.squares
    r = np.sqrt(r2)
    e = np.exp(-SQRT5 * r)
    k = np.zeros((n, n), order="F")
    k[pr.rows, pr.cols] = (1.0 + SQRT5 * r + (5.0 / 3.0) * r2) * e
    k.flat[:: n + 1] = 1.0 + nugget
    chol, info = dpotrf(k, lower=1, overwrite_a=1, clean=1)
    if info != 0:
        return 1e12, np.zeros_like(params)
    logdet_k = 2 * np.log(np.diag(chol)).sum()
    kinv, info = dpotri(chol, lower=1, overwrite_c=1)
    if info != 0:
        return 1e12, np.zeros_like(params)
    kinv = np.tril(kinv) + np.tril(kinv, -1).T
    p_dim = pr.h.shape[1]
    kh = kinv @ pr.h
    hk = pr.h.T @ kh
    try:
        hk_chol = np.linalg.cholesky(hk)
    except np.linalg.LinAlgError:
        return 1e12, np.zeros_like(params)
    pm = kinv - kh @ cho_solve((hk_chol, True), kh.T)
    a = pm @ ys                                               # (n, m)
    s2 = np.einsum("nm,nm->m", ys, a) / (n - p_dim)
    if not np.all(s2 > 0):
        return 1e12, np.zeros_like(params)
    value = 0.5 * ((n - p_dim) * float(np.log(s2).sum())
                   + m * (logdet_k + 2 * np.log(np.diag(hk_chol)).sum()))
    # tr(W dK_j) over the full symmetric matrices = 2 sum over the pairs (dK_j's diagonal
    # is zero): dk/dlog l_j = 5/3 (1 + sqrt5 r) exp(-sqrt5 r) (x_i - x_j)^2 / l_j^2
    aw = a / np.sqrt(s2)
    w = m * pm[pr.rows, pr.cols] - np.einsum("pm,pm->p", aw[pr.rows], aw[pr.cols])
    grad = np.empty_like(params)
    grad[:d] = inv_l2 * (pr.squares @ (w * (5.0 / 3.0) * (1.0 + SQRT5 * r) * e))
    grad[d] = 0.5 * nugget * (m * float(np.trace(pm)) - float(np.einsum("nm,nm->", aw, aw)))
    return value, grad


def from_hyperparameters(x: np.ndarray, y: np.ndarray, lengths: np.ndarray,
                         nugget: float, chol: np.ndarray | None = None) -> GaussianProcess:
    """The GP conditioned on (x, y) for given length scales and nugget (the signal
    variance profiled out). ``chol``: the kernel's Cholesky factor when already made (a
    GP with the same x, lengths and nugget: outputs sharing a kernel)."""
    chol, hk_chol, beta, resid = _factor(x, y, lengths, nugget, chol)
    varying = varying_inputs(x)
    n, p = len(y), int(varying.sum()) + 1
    s2 = float(resid @ resid) / max(n - p, 1)
    alpha = cho_solve((chol, True), y - basis(x, varying) @ beta)
    return GaussianProcess(x=x, y=y, lengths=lengths, signal_var=s2, nugget=nugget,
                           beta=beta, alpha=alpha, chol=chol, hk_chol=hk_chol,
                           varying=varying)


def fit_gp(x: np.ndarray, y: np.ndarray, starts: int = 4, seed: int = 0,
           min_nugget: float = NUGGET_BOUNDS[0],
           warm: GaussianProcess | None = None) -> GaussianProcess:
    """Maximise the restricted likelihood over (log lengths, log nugget), from ``starts``
    starting points: the first at ``warm``'s hyperparameters when given (a neighbouring
    output's fit), else at length 0.6 everywhere."""
    return fit_shared_gps(x, np.asarray(y, float)[:, None], starts, seed, min_nugget,
                          warm)[0]


def fit_shared_gps(x: np.ndarray, y: np.ndarray, starts: int = 4, seed: int = 0,
                   min_nugget: float = NUGGET_BOUNDS[0],
                   warm: GaussianProcess | None = None) -> tuple[GaussianProcess, ...]:
    """One GP per column of ``y`` (n, m), all with one kernel (length scales and nugget)
    that maximises the sum of their restricted likelihoods (``fit_gp``'s starts); each
    its own signal variance and mean. A query's variance is then one product for all m
    (``VectorGP.predict``). The nugget is the smallest any column's interpolation cap
    allows (below)."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    n, d = x.shape
    if n < int(varying_inputs(x).sum()) + 3:
        raise ValueError(f"{n} training points for {d} inputs: too few")
    rng = np.random.default_rng(seed)
    bounds = ([tuple(np.log(LENGTH_BOUNDS))] * d
              + [(np.log(max(min_nugget, NUGGET_BOUNDS[0])), np.log(NUGGET_BOUNDS[1]))])
    best = None
    pairs = TrainingPairs.of(x)
    for i in range(starts):
        lengths0 = np.full(d, 0.6) if i == 0 else np.exp(rng.uniform(np.log(0.2),
                                                                      np.log(3.0), d))
        # nugget starts at 1e-6 and, every other start, at the bound: the likelihood is
        # flat in a small nugget, so L-BFGS-B stays near where it starts
        nugget0 = 1e-6 if i % 2 == 0 else NUGGET_BOUNDS[0]
        if warm is not None and i == 0:
            lengths0, nugget0 = np.clip(warm.lengths, *LENGTH_BOUNDS), warm.nugget
        elif warm is not None and i == 1:
            lengths0 = np.full(d, 0.6)
        x0 = np.concatenate((np.log(lengths0), [np.log(max(nugget0, min_nugget))]))
        res = minimize(_neg_reml, x0, args=(x, y, pairs), jac=True, method="L-BFGS-B",
                       bounds=bounds, options={"maxiter": 300})
        if best is None or res.fun < best.fun:
            best = res
    assert best is not None
    lengths, nugget = np.exp(best.x[:d]), float(np.exp(best.x[d]))
    gps = _conditioned(x, y, lengths, nugget)
    # The data are FE curves, not noisy measurements: keep the nugget's absolute sd below
    # INTERPOLATION_SD of the outputs' spread, so that the GP reproduces its database
    # designs (a smooth, long-length-scale score has a large signal variance, and a
    # relative nugget of 1e-6 would then smooth it by 2 % of its spread).
    cap = min((INTERPOLATION_SD * float(np.std(y[:, j]))) ** 2 / g.signal_var
              for j, g in enumerate(gps))
    if nugget > cap:
        nugget = cap if cap > NUGGET_BOUNDS[0] else NUGGET_BOUNDS[0]
        gps = _conditioned(x, y, lengths, nugget)
    return tuple(gps)


def _conditioned(x: np.ndarray, y: np.ndarray, lengths: np.ndarray, nugget: float
                 ) -> list[GaussianProcess]:
    """One GP per column of ``y`` with one kernel, factorised once."""
    first = from_hyperparameters(x, y[:, 0], lengths, nugget)
    return [first] + [from_hyperparameters(x, y[:, j], lengths, nugget, first.chol)
                      for j in range(1, y.shape[1])]
