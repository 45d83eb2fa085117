"""The node values of database curves that ended early, for designs that end early too.

A group's curve GPs (``curve_gps``) are fitted on its complete curves (0 to 90 deg); a
database curve that ended early (the FE's 500 ul volume stop, a Newton failure near a
pressure maximum) reaches only its first nodes, and until 2026-12-05 it only bounded the
FE range. Near its end such a curve levels off (the balloon grows more than the actuator
bends) or steepens (a pressure maximum), a shape the complete curves do not have, so the
complete-curve GPs missed the FE curves of random designs that end early on 44 of 64
(twenty-second session). Conditioning every node's GP also on the early-ended curves that
reach it (the same kernel: its length scales and nugget kept) fixes much of that, but the
same rows pull the answers for nearby designs that do reach 90 deg the wrong way (PDMS on
Ecoflex: complete test curves within the target 201 -> 195 of 221 by pressure).

So both means are kept and blended by where the design's own FE curve is emulated to end
(``PairEmulator.range_model``, its mean): the complete-curve mean above BLEND_DEG[1], the
conditioned one below BLEND_DEG[0], linear in between (``early_weight``); each early-ended
curve without its last reached node (``short_of_the_end``). On the FE curves of the random
designs outside the database (band calibration set and the five held-out sets; `python
benchmarks/emulator_random_curves.py`), curves within the per-curve target, complete /
early-ended (benchmarks/RESULTS.md, twenty-fourth session):

    by pressure   381 / 20 of 415 / 64  ->  384 / 36
    by volume     365 / 12 of 414 / 62  ->  366 / 22

(blend ranges 50-70 to 75-95 deg measured with GP means, 60-80 among the best on both
axes; conditioning for every design lost complete curves: PDMS on Ecoflex 201 -> 195 of
221 by pressure, Ecoflex/Ecoflex 49 -> 17 of 61 by volume).

The variance is the complete-curve GPs' plus the blend's spread, w (m_conditioned -
m_complete)^2 (``CurveGPs``): where the two readings of the database disagree the answer
is not surer than that (held-out volume band coverage 0.948 -> 0.963, its worst set 0.854
-> 0.927); the band is then calibrated on the answers, FE curves of random designs
(``random_calibration``).

Cost: the rows an output uses are the complete curves and the early-ended curves that
reach its node; ordered by how far they reach, every output's rows are a leading block of
one order, so the pressure nodes (one kernel) need one Cholesky factor for all 32 (a
leading block of it is the factor of the leading block). A query computes the conditioned
means only where the weight is above 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_triangular

from surrogate.emulator.features import ANGLE_NODES_DEG
from surrogate.emulator.gp import (
    GaussianProcess,
    basis,
    from_hyperparameters,
    matern52,
    matern52_in_place,
)
from surrogate.emulator.vector_gp import CHUNK_ROWS, VectorGP

BLEND_DEG = (60.0, 80.0)   # emulated end (deg): conditioned mean below, complete-curve above
# unit-cube distance from an early-ended database curve within which the conditioned mean
# is blended in whatever the emulated end (1 at the curve, 0 at this distance): the
# emulated end is a smooth GP that puts an early-ended database design's own end at 61-90
# deg, so with its weight alone the design's own FE curve was not reproduced (by pressure
# 358 -> 395 of 565 within 0.2 deg; thirty-eighth session). Half the typical distance
# between neighbouring database designs, so random designs far from them are unchanged.
AT_CURVE_RADIUS = 0.05


def short_of_the_end(y: np.ndarray, n_nodes: int, last_step_from_deg: np.ndarray
                     ) -> np.ndarray:
    """Node outputs ``y`` (m, 2 n_nodes: pressure nodes, then volume nodes; NaN past each
    curve's end) without each curve's last reached node on either axis where that node
    lies in the FE's last step (above ``last_step_from_deg``, per curve: the angle the
    step started from), which the stop interrupts (the volume stop within the step, a
    Newton failure at a pressure maximum), where the interpolated curve is least sure.
    Dropping it on the FE curves of random designs, curves within the per-curve target
    (complete / early-ended, emulator answers): by pressure 381 / 36 -> 384 / 36 and by
    volume 363 / 19 -> 366 / 22 of 415 / 64 and 414 / 62 (twenty-fourth session). A node
    below the last step is an interpolated FE value like any other: keeping it took the
    early-ended database curves reproduced within 0.2 deg by pressure 372 -> 424 of 565
    (thirty-eighth session; benchmarks/RESULTS.md)."""
    out = np.array(y, float)
    reach = np.isfinite(out[:, :n_nodes]).sum(1)
    for i, r in enumerate(reach):
        if r and ANGLE_NODES_DEG[r - 1] > last_step_from_deg[i]:
            out[i, r - 1] = out[i, n_nodes + r - 1] = np.nan
    return out


def early_weight(end_deg: np.ndarray | float) -> np.ndarray:
    """The conditioned mean's weight for a design whose FE curve is emulated to end at
    ``end_deg`` (deg): 1 below BLEND_DEG[0], 0 above BLEND_DEG[1], linear between."""
    lo, hi = BLEND_DEG
    return np.clip((hi - np.asarray(end_deg, float)) / (hi - lo), 0.0, 1.0)


def at_curve_weight(distance: np.ndarray | float) -> np.ndarray:
    """The conditioned mean's weight for a design ``distance`` (unit cube) from the
    nearest early-ended database curve of its direction: 1 - distance / AT_CURVE_RADIUS,
    0 beyond (``AT_CURVE_RADIUS``). The blend's weight is the larger of this and
    ``early_weight``."""
    return np.clip(1.0 - np.asarray(distance, float) / AT_CURVE_RADIUS, 0.0, 1.0)


@dataclass(frozen=True)
class EarlyEndedRows:
    """The early-ended database curves of a pair: unit coordinates ``u`` (m, d) and their
    GP outputs ``y`` (m, c) in output units, NaN where the curve did not reach the node."""

    u: np.ndarray
    y: np.ndarray

    def __post_init__(self) -> None:
        u, y = np.asarray(self.u, float), np.asarray(self.y, float)
        if u.ndim != 2 or y.ndim != 2 or len(u) != len(y) or not np.isfinite(u).all():
            raise ValueError("early-ended rows: u (m, d) finite and y (m, c) with the same m")
        reach = np.isfinite(y).sum(1)
        order = np.argsort(-reach, kind="stable")
        # every output's rows a leading block of that order: a curve reaches a node only
        # when it reaches every node before it (and with it the outputs of that node)
        if not all(np.isfinite(y[order, j])[:int(np.isfinite(y[:, j]).sum())].all()
                   for j in range(y.shape[1])):
            raise ValueError("early-ended rows: each curve's outputs must be its first "
                             "nodes (reached) then NaN")
        object.__setattr__(self, "u", u[order])
        object.__setattr__(self, "y", y[order])


def _extended_factor(g: GaussianProcess, extra: np.ndarray) -> np.ndarray:
    """The lower Cholesky factor of the kernel matrix of ``g``'s training inputs and then
    the rows ``extra`` (g's correlation and nugget), from g's own factor L: the block
    [[L, 0], [B, C]] with B = (L^-1 K_xe)^T and C C^T = K_ee + g I - B B^T (n^2 m work,
    not (n + m)^3 / 3). A leading block of it is the factor of the leading block."""
    n, m = len(g.y), len(extra)
    b = solve_triangular(g.chol, matern52(g.x, extra, g.lengths), lower=True).T   # (m, n)
    c = np.linalg.cholesky(matern52(extra, extra, g.lengths) + g.nugget * np.eye(m)
                           - b @ b.T)
    out = np.zeros((n + m, n + m))
    out[:n, :n] = g.chol
    out[n:, :n] = b
    out[n:, n:] = c
    return out


@dataclass(frozen=True)
class ConditionedMeans:
    """Means-only GPs of every output of ``gp`` (a VectorGP with identity components)
    conditioned on its own rows and on the early-ended ``rows`` that reach the output
    (hyperparameters kept). ``predict_many`` gives (N, c) means in output units."""

    gp: VectorGP
    rows: EarlyEndedRows

    def __post_init__(self) -> None:
        gps, rows = self.gp.gps, self.rows
        if not self.gp.per_output or rows.y.shape[1] != len(gps):
            raise ValueError("early-ended rows: one output per curve GP needed")
        x_all = np.vstack((gps[0].x, rows.u))
        n_all = len(x_all)
        z = (rows.y - self.gp.center) / self.gp.scale
        alpha = np.zeros((len(gps), n_all))
        beta = np.zeros((len(gps), gps[0].beta.size))
        n, size = len(gps[0].y), len(gps[0].y) + int(np.isfinite(z).any(1).sum())
        by_kernel: dict[bytes, list[int]] = {}
        for j, g in enumerate(gps):
            by_kernel.setdefault(g.lengths.tobytes() + np.float64(g.nugget).tobytes(),
                                 []).append(j)
        for outputs in by_kernel.values():     # one factor per kernel, then let go
            chol = _extended_factor(gps[outputs[0]], rows.u[:size - n])
            for j in outputs:
                g = gps[j]
                m = n + int(np.isfinite(z[:, j]).sum())
                c = from_hyperparameters(x_all[:m], np.concatenate((g.y, z[:m - n, j])),
                                         g.lengths, g.nugget, chol[:m, :m])
                alpha[j, :m] = c.alpha
                beta[j] = c.beta
        # outputs that share a kernel share its correlations with a query: one per kernel
        inv_l2 = np.array([1.0 / g.lengths**2 for g in gps])
        kernels, kernel_of = np.unique(inv_l2, axis=0, return_inverse=True)
        object.__setattr__(self, "_x", x_all)
        object.__setattr__(self, "_inv_l2", kernels)
        object.__setattr__(self, "_kernel_of", kernel_of.ravel())
        object.__setattr__(self, "_outputs", [np.flatnonzero(kernel_of.ravel() == q)
                                              for q in range(len(kernels))])
        object.__setattr__(self, "_alpha", alpha)
        object.__setattr__(self, "_beta", beta)
        object.__setattr__(self, "_varying", gps[0].varying)

    def predict(self, u: np.ndarray) -> np.ndarray:
        """The conditioned means (c,), output units, at one input row ``u``."""
        u = np.asarray(u, float).ravel()
        d2 = (self._x - u) ** 2  # type: ignore[attr-defined]                 # (n, d)
        k = matern52_in_place(self._inv_l2 @ d2.T)  # type: ignore[attr-defined]
        h = np.concatenate(([1.0], u[self._varying]))  # type: ignore[attr-defined]
        z = self._beta @ h + np.einsum(  # type: ignore[attr-defined]
            "cn,cn->c", k[self._kernel_of], self._alpha)  # type: ignore[attr-defined]
        return self.gp.center + self.gp.scale * z

    def predict_many(self, u: np.ndarray) -> np.ndarray:
        """The conditioned means (N, c), output units, at the rows of ``u`` (N, d): one
        correlation vector per distinct kernel (the 32 pressure nodes share one)."""
        u = np.atleast_2d(np.asarray(u, float))
        if len(u) > CHUNK_ROWS:     # bounded temporaries: (kernels, CHUNK_ROWS, n) at most
            return np.concatenate([self.predict_many(u[i:i + CHUNK_ROWS])
                                   for i in range(0, len(u), CHUNK_ROWS)])
        x = self._x  # type: ignore[attr-defined]
        d2 = (u.T[:, :, None] - x.T[:, None, :]) ** 2                          # (d, N, n)
        r2 = (self._inv_l2 @ d2.reshape(len(x.T), -1)).reshape(  # type: ignore[attr-defined]
            -1, len(u), len(x))
        k = matern52_in_place(r2)                                           # (kernels, N, n)
        h = basis(u, self._varying)  # type: ignore[attr-defined]
        z = h @ self._beta.T  # type: ignore[attr-defined]
        for kq, cols in zip(k, self._outputs, strict=True):  # type: ignore[attr-defined]
            z[:, cols] += kq @ self._alpha[cols].T  # type: ignore[attr-defined]
        return self.gp.center + self.gp.scale * z
