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

Here the length scales and nugget (one kernel for all nodes, as ``build.fit_force_gps``)
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

from surrogate.emulator.gp import from_hyperparameters
from surrogate.emulator.vector_gp import VectorGP, fit_output_gps, vector_gp_from_dict


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

    @property
    def gps(self) -> tuple:
        """Every node's GP, in node order."""
        return tuple(g for s in self.segments for g in s.gps)

    @property
    def center(self) -> np.ndarray:
        return np.concatenate([s.center for s in self.segments])

    def predict(self, u: np.ndarray, variance_of=None) -> tuple[np.ndarray, np.ndarray]:
        """Mean and variance at every node for one input row ``u``."""
        parts = [s.predict(u, variance_of) for s in self.segments]
        return np.concatenate([m for m, _ in parts]), np.concatenate([v for _, v in parts])

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
