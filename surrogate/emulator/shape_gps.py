"""GPs of a pair's node outputs read with the shape of the design's pressure curve.

Two sets of a pair's node outputs are steep functions of the design that the shape of its
pressure curve straightens out, so their GPs take, besides the design's unit coordinates u,
the shape s of the pressure curve: the differences of log(p/theta) between a few angle
nodes (``pressure_shape``), scaled to [0, 1] over the fitted designs.

- The volume nodes (``VOLUME_SHAPE_NODES_DEG`` 10, 30, 60, 90 deg). A free-tip curve's
  injected volume at a bending angle is the chamber's growth: the bending's share and the
  membrane's balloon. Near 60-90 deg the balloon takes most of it, and how much depends on
  how close the chamber pressure is to the membrane's own pressure maximum, which is what
  flattens the pressure curve there. On the complete FE curves of random designs outside
  the database (twenty-sixth session) within the per-curve target by volume: PDMS on
  Ecoflex 208 -> 218 of 240, the reversed pair 110 -> 120 of 126.
- The pressure nodes from 45 deg up (``TOP_PRESSURE_FROM_DEG``; shape nodes
  ``TOP_SHAPE_NODES_DEG`` 5, 15, 30, 40 deg). Where the curve flattens towards the
  membrane's pressure maximum a small error in log p is a large one in angle; how the
  curve bends below 45 deg tells how soon it flattens above. Within the per-curve target
  by pressure, GP means as a query reads them (twenty-seventh session): the reversed pair
  114 -> 122 of 126, Ecoflex/Ecoflex bending away 54 -> 62 of 67, PDMS on Ecoflex 215 ->
  218 of 240; the top nodes given their own kernel without the shape 115 and 55. The
  refitted emulator on every free-tip FE curve of random designs it did not see: by
  pressure complete 384 -> 392 of 415, early-ended 47 -> 45 of 77 (benchmarks/RESULTS.md,
  twenty-seventh session; some designs lost, more gained).

Both are fitted on s read off the pressure GPs' leave-one-out means at the fitted designs
(exact, hyperparameters kept), not the FE's own nodes, so that an input is as uncertain in
the fit as in a query (with the FE's nodes the reversed pair's volume got worse: 110 -> 108
of 126, against 110 -> 122). A query reads s off the pressure GPs' means less the
leave-one-out error of s interpolated from the fitted designs by the pressure GPs' kernel,

    s(u) = s_mean(u) - k(u)^T K^-1 (s_i - s_loo,i),

which is s_loo at a fitted design (so its FE curve is reproduced: the plain s_mean put a
database curve 1.4 deg off by volume) and s_mean away from them (the correction cost 2-4
of the volume curves the shape gained).

Variance: the shape GPs' own, the shape taken as known; the band multipliers are
calibrated on these answers (cross-validation, then FE curves of random designs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_solve

from surrogate.emulator.features import ANGLE_NODES_DEG
from surrogate.emulator.gp import matern52
from surrogate.emulator.vector_gp import (
    CHUNK_ROWS,
    VectorGP,
    fit_output_gps,
    vector_gp_from_dict,
)

VOLUME_SHAPE_NODES_DEG = (10.0, 30.0, 60.0, 90.0)
TOP_SHAPE_NODES_DEG = (5.0, 15.0, 30.0, 40.0)
TOP_PRESSURE_FROM_DEG = 45.0
TOP_PRESSURE_FROM = int(np.flatnonzero(np.isclose(ANGLE_NODES_DEG, TOP_PRESSURE_FROM_DEG))[0])
# the fewest designs a group's top pressure GPs are fitted from (their 9 inputs: about 10
# designs per input; the shipped groups have 205-479). With 16 designs the top nodes' GPs
# put a kink at 40-45 deg into a curve the pressure GPs alone drew smoothly, and the
# force model, linear in F / theta between its pressure nodes, missed a database design's
# blocked-tip force by 10 % between its top nodes (tests/test_emulator.py)
TOP_PRESSURE_MIN_DESIGNS = 100


def shape_node_indices(nodes_deg: tuple[float, ...] | np.ndarray) -> np.ndarray:
    """The angle nodes at ``nodes_deg`` (ValueError unless at least two increasing nodes)."""
    nodes = np.asarray(nodes_deg, float).ravel()
    idx = [np.flatnonzero(np.isclose(ANGLE_NODES_DEG, a)) for a in nodes]
    if len(nodes) < 2 or any(i.size != 1 for i in idx) or (np.diff(nodes) <= 0).any():
        raise ValueError("shape nodes must be at least two increasing angle nodes (deg)")
    return np.array([int(i[0]) for i in idx])


def pressure_shape(log_p: np.ndarray,
                   nodes_deg: tuple[float, ...] | np.ndarray = VOLUME_SHAPE_NODES_DEG
                   ) -> np.ndarray:
    """The pressure curve's shape (..., len(nodes_deg) - 1) from its pressure nodes
    ``log_p`` (..., 32: log(p_k / theta_k)): the differences of log(p / theta) between the
    nodes at ``nodes_deg`` (how much stiffer or softer per degree the curve grows between
    them)."""
    return _shape(log_p, shape_node_indices(nodes_deg))


def _shape(log_p: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """``pressure_shape`` at the angle-node indices ``nodes``."""
    return np.diff(np.asarray(log_p, float)[..., nodes], axis=-1)


def loo_pressure_means(gp: VectorGP, n_outputs: int) -> np.ndarray:
    """The leave-one-out means (n, n_outputs) of ``gp``'s first ``n_outputs`` outputs (one
    GP per output, hyperparameters kept) at its training rows; outputs that share a kernel
    share its n x n work."""
    if not gp.per_output:
        raise ValueError("leave-one-out pressure means need one GP per output")
    gps = gp.gps[:n_outputs]
    out = np.empty((len(gps[0].y), n_outputs))
    projector: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}
    for j, g in enumerate(gps):
        key = g.lengths.tobytes() + np.float64(g.nugget).tobytes()
        if key not in projector:
            projector[key] = g.loo_projector()
        p, d = projector[key]
        z_loo = g.y - (p @ g.y) / d                      # standardised units
        out[:, j] = gp.center[j] + gp.scale[j] * z_loo
    return out


@dataclass(frozen=True)
class ShapeGPs:
    """GPs of some of a pair's node outputs over the unit coordinates and the pressure
    curve's shape between the nodes at ``shape_nodes_deg``, scaled by ``shape_low`` and
    ``shape_span`` (the fitted designs' range). ``pressure_lengths`` are the pressure GPs'
    kernel length scales and ``shape_alpha`` (n, k) = K^-1 (s_i - s_loo,i) over the fitted
    designs (the GPs' own first inputs), scaled: the query's correction."""

    gp: VectorGP
    shape_nodes_deg: tuple[float, ...]
    shape_low: np.ndarray
    shape_span: np.ndarray
    pressure_lengths: np.ndarray
    shape_alpha: np.ndarray

    def __post_init__(self) -> None:
        # the shape nodes' indices once, not per query (a query is a few ms)
        object.__setattr__(self, "_shape_nodes", shape_node_indices(self.shape_nodes_deg))

    def inputs(self, u: np.ndarray, log_p: np.ndarray,
               pressure_rows: np.ndarray | None = None) -> np.ndarray:
        """The GP inputs at designs ``u`` (N, d) with pressure nodes ``log_p`` (N, 32):
        ``u`` and the scaled shape, corrected by the fitted designs' leave-one-out error.
        ``pressure_rows`` (N, n): the pressure GPs' kernel rows at ``u`` when the caller
        has them (``CurveGPs``, where those GPs were fitted on these designs with
        ``pressure_lengths``; a query's correction then costs no kernel of its own)."""
        u = np.atleast_2d(np.asarray(u, float))
        s = (_shape(np.atleast_2d(log_p), self._shape_nodes)  # type: ignore[attr-defined]
             - self.shape_low) / self.shape_span
        if pressure_rows is not None:
            s -= np.atleast_2d(pressure_rows) @ self.shape_alpha
            return np.concatenate((u, s), axis=-1)
        x = self.design_inputs
        for i in range(0, len(u), CHUNK_ROWS):      # bounded temporaries: (rows, n)
            s[i:i + CHUNK_ROWS] -= (matern52(u[i:i + CHUNK_ROWS], x, self.pressure_lengths)
                                    @ self.shape_alpha)
        return np.concatenate((u, s), axis=-1)

    @property
    def design_inputs(self) -> np.ndarray:
        """The fitted designs' unit coordinates (n, d): the GPs' inputs before the shape."""
        return self.gp.gps[0].x[:, :len(self.pressure_lengths)]

    def predict(self, u: np.ndarray, log_p: np.ndarray,
                variance_of: slice | np.ndarray | None = None,
                pressure_rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Means and variances of the outputs at one design (``VectorGP.predict``;
        ``pressure_rows`` as in ``inputs``)."""
        return self.gp.predict(self.inputs(np.ravel(u), np.ravel(log_p), pressure_rows)[0],
                               variance_of)

    def predict_many(self, u: np.ndarray, log_p: np.ndarray,
                     variance_of: slice | np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
        """``predict`` at the rows of ``u`` (N, d) with pressure nodes ``log_p`` (N, 32)."""
        return self.gp.predict_many(self.inputs(u, log_p), variance_of)

    def as_dict(self) -> dict[str, object]:
        return {"gp": self.gp.as_dict(), "shape_nodes_deg": list(self.shape_nodes_deg),
                "shape_low": self.shape_low.tolist(),
                "shape_span": self.shape_span.tolist(),
                "pressure_lengths": self.pressure_lengths.tolist(),
                "shape_alpha": self.shape_alpha.tolist()}


def shape_scaling(d: dict, name: str, default_nodes_deg: tuple[float, ...]
                  ) -> tuple[tuple[float, ...], np.ndarray, np.ndarray, np.ndarray,
                             np.ndarray]:
    """A stored ShapeGPs' (field ``name`` of the file) ``shape_nodes_deg`` (absent: the
    default, as format 13 stored the volume GPs), ``shape_low``, ``shape_span``,
    ``pressure_lengths`` and ``shape_alpha`` (ValueError naming ``name`` unless increasing
    angle nodes, one finite number per shape for the first two, the spans positive,
    positive lengths and finite (n, shapes) weights): checked before its GPs are built."""
    try:
        nodes = tuple(float(a) for a in d.get("shape_nodes_deg", default_nodes_deg))
        shape_node_indices(nodes)
        low, span, lengths, alpha = (np.asarray(d[k], float) for k in (
            "shape_low", "shape_span", "pressure_lengths", "shape_alpha"))
    except (TypeError, ValueError):
        raise ValueError(f"{name}: shape_nodes_deg (increasing angle nodes), shape_low, "
                         "shape_span, pressure_lengths and shape_alpha must be numbers"
                         ) from None
    n_shape = len(nodes) - 1
    if low.shape != (n_shape,) or span.shape != low.shape \
            or not (np.isfinite(low).all() and np.isfinite(span).all() and (span > 0).all()):
        raise ValueError(f"{name}: shape_low and shape_span must be {n_shape} finite "
                         "numbers, the spans positive")
    if lengths.ndim != 1 or not (np.isfinite(lengths).all() and (lengths > 0).all()):
        raise ValueError(f"{name}: pressure_lengths must be positive numbers")
    if alpha.ndim != 2 or alpha.shape[1] != n_shape or not np.isfinite(alpha).all():
        raise ValueError(f"{name}: shape_alpha must be finite numbers, {n_shape} per design")
    return nodes, low, span, lengths, alpha


def shape_gps_from_dict(d: dict, name: str, default_nodes_deg: tuple[float, ...]
                        ) -> ShapeGPs:
    """The ShapeGPs stored as field ``name`` (``ShapeGPs.as_dict``; ValueError naming it)."""
    shape = ShapeGPs(vector_gp_from_dict(d["gp"]), *shape_scaling(d, name, default_nodes_deg))
    x = shape.gp.gps[0].x
    if (len(shape.shape_alpha) != len(x)
            or x.shape[1] != len(shape.pressure_lengths) + len(shape.shape_low)):
        raise ValueError(f"{name}: shape_alpha needs one row per fitted design and "
                         "pressure_lengths one per input before the shape")
    return shape


def fit_shape_gps(u: np.ndarray, outputs: np.ndarray, pressure_gp: VectorGP,
                  shape_nodes_deg: tuple[float, ...], shared: bool, seed: int = 0
                  ) -> ShapeGPs:
    """GPs of ``outputs`` (n, c) at the fitted designs' unit coordinates ``u`` (n, d) read
    with the pressure curve's shape between ``shape_nodes_deg``, from the pressure GPs
    fitted to the same designs (their first 32 outputs the pressure nodes, one kernel:
    ``build.fit_curve_gps``): fitted on the shape of the pressure GPs' leave-one-out means,
    the outputs sharing one kernel (``shared``) or each its own; the correction that turns
    a query's shape into that at the fitted designs."""
    u = np.asarray(u, float)
    n_p = len(ANGLE_NODES_DEG)
    log_p = pressure_gp.center[:n_p] + pressure_gp.scale[:n_p] * np.column_stack(
        [g.y for g in pressure_gp.gps[:n_p]])
    s_loo = pressure_shape(loo_pressure_means(pressure_gp, n_p), shape_nodes_deg)
    low = s_loo.min(0)
    span = np.maximum(s_loo.max(0) - low, 1e-6)
    scaled_loo = (s_loo - low) / span
    kernel = pressure_gp.gps[0]
    alpha = cho_solve((kernel.chol, True),
                      (pressure_shape(log_p, shape_nodes_deg) - low) / span - scaled_loo)
    gp = fit_output_gps(np.column_stack((u, scaled_loo)), outputs, seed=seed,
                        shared=slice(0, outputs.shape[1]) if shared else None)
    # C order, as a stored file gives it back: the query's product then sums in the same
    # order, and a saved emulator answers bit for bit as the fitted one
    return ShapeGPs(gp, tuple(float(a) for a in shape_nodes_deg), low, span,
                    kernel.lengths.copy(), np.ascontiguousarray(alpha))
