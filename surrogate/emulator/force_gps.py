"""The blocked-tip force GPs, each node conditioned on every design that reaches it.

The force variable (``features.force_angle_feature``: the blocked tip's force over the
free tip's emulated angle at the same pressure) is known at a group's force nodes up to
where each design's blocked-tip FE curve ends (a pressure maximum, the volume stop) or its
free curve passes 90 deg. Until 2026-12-06 the GPs were fitted on the designs that reach
every node of the group's force range alone (60 of 92 PDMS-bodied designs to 2500 Pa),
so near the top of the force the box gives -- where many blocked-tip curves end soon past
2000 Pa and their force flattens -- they extrapolated from designs that run on: the
three designs an inverse design listed for 1 mN at 2000 Pa had FE forces 15-21 % below
the answer (0.85, 0.80, 0.79 mN).

Here the length scales and nugget (one kernel for all nodes, as ``force_fit.fit_force_gps``)
are still fitted on the designs that reach every node, but each node's GP is conditioned
on every design that reaches it (83-92 PDMS-bodied designs below 2500 Pa). A design
reaches a prefix of the nodes, so the nodes split into a few consecutive segments with
one training set each; each segment is a VectorGP sharing one kernel (a query's force is
one product per segment). Those three designs: 0.85 / 0.85 / 0.88 mN answered, bands
covering the FE (benchmarks/RESULTS.md, thirty-ninth session).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.emulator.gp import from_hyperparameters, matern52_in_place
from surrogate.emulator.vector_gp import (
    VectorGP,
    _a_inv,
    _kinv_h,
    _linv,
    fit_output_gps,
    vector_gp_from_dict,
)


def nodes_reached(y: np.ndarray) -> np.ndarray:
    """How many leading nodes of each row of ``y`` (n, k) are finite."""
    return np.isfinite(np.asarray(y, float)).cumprod(axis=1).sum(axis=1)


@dataclass(frozen=True)
class ForceGPs:
    """The force variable at a group's force nodes: ``segments``, consecutive runs of
    nodes (in order) each conditioned on the designs that reach its last node, sharing
    the length scales and nugget of one kernel fitted on the designs that reach every
    node. Answers as a VectorGP does (``predict``, ``predict_many``)."""

    segments: tuple[VectorGP, ...]

    def __post_init__(self) -> None:
        # One query's arrays, all segments stacked over the first segment's rows (every
        # later training set is a subset of it; a segment's arrays are zero at the rows
        # it lacks): L^-1 of each kernel, K^-1 H, A^-1, and every output's GLS
        # coefficients, alpha, signal variance and segment. A query is one kernel row and
        # a few batched products (each segment's own VectorGP.predict took 30-40 us,
        # mostly call overhead: 5 segments tripled the force's share of a first query).
        first = self.segments[0].gps[0]
        n = len(first.x)
        place = {row.tobytes(): i for i, row in enumerate(first.x)}
        linv = np.zeros((len(self.segments), n, n))
        kinv_h = np.zeros((len(self.segments), n, len(first.beta)))
        alpha = np.zeros((sum(len(seg.gps) for seg in self.segments), n))
        a_inv, segment_of, out = [], [], 0
        for q, seg in enumerate(self.segments):
            gp = seg.gps[0]
            if not np.array_equal(gp.varying, first.varying):
                raise ValueError("force GPs: segments with different mean bases")
            idx = np.array([place[row.tobytes()] for row in gp.x])
            linv[q][np.ix_(idx, idx)] = _linv(gp)
            kinv_h[q][idx] = _kinv_h(gp)
            a_inv.append(_a_inv(gp))
            for g in seg.gps:
                alpha[out, idx] = g.alpha
                segment_of.append(q)
                out += 1
        gps = self.gps
        object.__setattr__(self, "_lean", {
            "x": first.x, "inv_l2": 1.0 / first.lengths**2, "varying": first.varying,
            "linv": linv, "kinv_h": kinv_h, "a_inv": np.array(a_inv), "alpha": alpha,
            "beta": np.array([g.beta for g in gps]),
            "s2": np.array([g.signal_var for g in gps]), "segment_of": np.array(segment_of),
            "center": self.center, "scale": np.concatenate([s.scale for s in self.segments])})

    @property
    def gps(self) -> tuple:
        """Every node's GP, in node order."""
        return tuple(g for s in self.segments for g in s.gps)

    @property
    def center(self) -> np.ndarray:
        return np.concatenate([s.center for s in self.segments])

    def predict(self, u: np.ndarray, variance_of=None) -> tuple[np.ndarray, np.ndarray]:
        """Mean and variance at every node for one input row ``u`` (``variance_of``: as
        VectorGP's; given, the segments' own predict answers)."""
        if variance_of is not None:
            parts = [s.predict(u, variance_of) for s in self.segments]
            return (np.concatenate([m for m, _ in parts]),
                    np.concatenate([v for _, v in parts]))
        st = self._lean  # type: ignore[attr-defined]
        u = np.asarray(u, float).ravel()
        k = matern52_in_place(((st["x"] - u) ** 2) @ st["inv_l2"], nonnegative=True)
        h = np.concatenate(([1.0], u[st["varying"]]))
        v = st["linv"] @ k                                           # (segments, n)
        rr = h - k @ st["kinv_h"]                                    # (segments, p)
        shared = np.maximum(1.0 - np.einsum("sn,sn->s", v, v)
                            + np.einsum("sp,spq,sq->s", rr, st["a_inv"], rr), 0.0)
        mean = st["center"] + st["scale"] * (st["beta"] @ h + st["alpha"] @ k)
        return mean, st["scale"] ** 2 * st["s2"] * shared[st["segment_of"]]

    def predict_many(self, u: np.ndarray, variance_of=None) -> tuple[np.ndarray, np.ndarray]:
        """Means and variances (N, nodes) at the rows of ``u``."""
        parts = [s.predict_many(u, variance_of) for s in self.segments]
        return (np.concatenate([m for m, _ in parts], axis=1),
                np.concatenate([v for _, v in parts], axis=1))

    def as_dict(self) -> dict[str, object]:
        return {"segments": [s.as_dict() for s in self.segments]}


def force_gps_from_dict(d: dict) -> VectorGP | ForceGPs:
    """The stored force GPs: segments (since file format 15) or one VectorGP (older)."""
    if "segments" in d:
        segments = tuple(vector_gp_from_dict(s) for s in d["segments"])
        if not segments:
            raise ValueError("force GPs: no segments")
        return ForceGPs(segments)
    return vector_gp_from_dict(d)


def fit_force_nodewise(u: np.ndarray, y: np.ndarray, seed: int = 0) -> ForceGPs:
    """The force GPs from designs ``u`` (n, 6) and the force variable ``y`` (n, k), NaN
    past each design's end: one kernel fitted on the rows that reach all k nodes
    (``fit_output_gps``, shared), then each node conditioned on every row that reaches it.
    ValueError when fewer than 2 rows reach every node."""
    u, y = np.asarray(u, float), np.asarray(y, float)
    k = y.shape[1]
    reach = nodes_reached(y)
    complete = reach >= k
    if complete.sum() < 2:
        raise ValueError("force GPs: fewer than 2 designs reach every force node")
    hyper = fit_output_gps(u[complete], y[complete], seed=seed, shared=slice(None))
    lengths, nugget = hyper.gps[0].lengths, hyper.gps[0].nugget
    segments, j = [], 0
    while j < k:
        rows = reach > j
        end = j + 1
        while end < k and np.array_equal(reach > end, rows):
            end += 1
        z = (y[rows, j:end] - hyper.center[j:end]) / hyper.scale[j:end]
        gps, chol = [], None
        for c in range(end - j):
            gp = from_hyperparameters(u[rows], z[:, c], lengths, nugget, chol)
            chol = gp.chol
            gps.append(gp)
        segments.append(VectorGP(hyper.center[j:end], hyper.scale[j:end],
                                 np.eye(end - j), tuple(gps), np.zeros(end - j)))
        j = end
    return ForceGPs(tuple(segments))
