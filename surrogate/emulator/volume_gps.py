"""The volume nodes of a pair, read with the shape of the design's pressure curve.

A free-tip curve's injected volume at a bending angle is the chamber's growth: the
bending's share and the membrane's balloon. Near 60-90 deg the balloon takes most of it,
and how much depends on how close the chamber pressure is to the membrane's own
pressure maximum, which is what flattens the pressure curve there. So the volume nodes
(log V / theta, above 30 deg the log of their rise, ``curve_gps``) are a function of the
design that the pressure curve's shape straightens out: their GPs take, besides the
design's unit coordinates u, the shape of its pressure curve,

    s = (log(p_30/30) - log(p_10/10), log(p_60/60) - log(p_30/30),
         log(p_90/90) - log(p_60/60))                         (``pressure_shape``)

scaled to [0, 1] over the fitted designs. The GPs are fitted on s read off the pressure
GPs' leave-one-out means at the fitted designs (exact, hyperparameters kept), not the FE's
own nodes, so that an input is as uncertain in the fit as in a query (with the FE's nodes
the reversed pair got worse: 110 -> 108 of 126 complete test curves, against 110 -> 122).
A query reads s off the pressure nodes' GP means (the curve it answers with) less the
leave-one-out error of s interpolated from the fitted designs by the pressure GPs' kernel,

    s(u) = s_mean(u) - k(u)^T K^-1 (s_i - s_loo,i),

which is s_loo at a fitted design (so its FE curve is reproduced on the volume axis too:
the plain s_mean put a database curve 1.4 deg off by volume) and s_mean away from them
(the correction cost 2-4 of the curves the shape gained: 208 -> 218 and 110 -> 120).

On the complete FE curves of random designs outside the database (band calibration set
and six held-out sets, GP means read as a query reads them; benchmarks/RESULTS.md,
twenty-sixth session), curves within the per-curve target by volume: PDMS on Ecoflex
208 -> 218 of 240, the reversed pair 110 -> 120 of 126.

Variance: the volume GPs' own, the shape taken as known; the band multipliers are
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

SHAPE_NODES_DEG = (10.0, 30.0, 60.0, 90.0)
_SHAPE_NODES = np.array([int(np.flatnonzero(np.isclose(ANGLE_NODES_DEG, a))[0])
                         for a in SHAPE_NODES_DEG])


def pressure_shape(log_p: np.ndarray) -> np.ndarray:
    """The pressure curve's shape (..., 3) from its pressure nodes ``log_p`` (..., 32:
    log(p_k / theta_k)): the differences of log(p / theta) between 10, 30, 60 and 90 deg
    (how much stiffer or softer per degree the curve grows between them)."""
    y = np.asarray(log_p, float)[..., _SHAPE_NODES]
    return np.diff(y, axis=-1)


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
class VolumeGPs:
    """GPs of a pair's volume outputs (rise outputs, ``curve_gps``) over the unit
    coordinates and the pressure curve's shape, scaled by ``shape_low`` and ``shape_span``
    (the fitted designs' range). ``pressure_lengths`` are the pressure GPs' kernel length
    scales and ``shape_alpha`` (n, 3) = K^-1 (s_i - s_loo,i) over the fitted designs (the
    GPs' own first inputs), scaled: the query's correction."""

    gp: VectorGP
    shape_low: np.ndarray
    shape_span: np.ndarray
    pressure_lengths: np.ndarray
    shape_alpha: np.ndarray

    def inputs(self, u: np.ndarray, log_p: np.ndarray) -> np.ndarray:
        """The GP inputs at designs ``u`` (N, d) with pressure nodes ``log_p`` (N, 32):
        ``u`` and the scaled shape, corrected by the fitted designs' leave-one-out error."""
        u = np.atleast_2d(np.asarray(u, float))
        s = (pressure_shape(np.atleast_2d(log_p)) - self.shape_low) / self.shape_span
        x = self.gp.gps[0].x[:, :u.shape[1]]
        for i in range(0, len(u), CHUNK_ROWS):      # bounded temporaries: (rows, n, d)
            s[i:i + CHUNK_ROWS] -= (matern52(u[i:i + CHUNK_ROWS], x, self.pressure_lengths)
                                    @ self.shape_alpha)
        return np.concatenate((u, s), axis=-1)

    def predict(self, u: np.ndarray, log_p: np.ndarray,
                variance_of: slice | np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray]:
        """Means and variances (32,) of the volume outputs at one design (``VectorGP``)."""
        return self.gp.predict(self.inputs(np.ravel(u), np.ravel(log_p))[0], variance_of)

    def predict_many(self, u: np.ndarray, log_p: np.ndarray,
                     variance_of: slice | np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
        """``predict`` at the rows of ``u`` (N, d) with pressure nodes ``log_p`` (N, 32)."""
        return self.gp.predict_many(self.inputs(u, log_p), variance_of)

    def as_dict(self) -> dict[str, object]:
        return {"gp": self.gp.as_dict(), "shape_low": self.shape_low.tolist(),
                "shape_span": self.shape_span.tolist(),
                "pressure_lengths": self.pressure_lengths.tolist(),
                "shape_alpha": self.shape_alpha.tolist()}


def shape_scaling(d: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A stored VolumeGPs' ``shape_low``, ``shape_span``, ``pressure_lengths`` and
    ``shape_alpha`` (ValueError unless 3 finite numbers each for the first two, the spans
    positive, positive lengths and finite (n, 3) weights): checked before its GPs are
    built."""
    try:
        low, span, lengths, alpha = (np.asarray(d[k], float) for k in (
            "shape_low", "shape_span", "pressure_lengths", "shape_alpha"))
    except (TypeError, ValueError):
        raise ValueError("volume_gps: shape_low, shape_span, pressure_lengths and "
                         "shape_alpha must be numbers") from None
    n_shape = len(SHAPE_NODES_DEG) - 1
    if low.shape != (n_shape,) or span.shape != low.shape \
            or not (np.isfinite(low).all() and np.isfinite(span).all() and (span > 0).all()):
        raise ValueError("volume_gps: shape_low and shape_span must be 3 finite numbers, "
                         "the spans positive")
    if lengths.ndim != 1 or not (np.isfinite(lengths).all() and (lengths > 0).all()):
        raise ValueError("volume_gps: pressure_lengths must be positive numbers")
    if alpha.ndim != 2 or alpha.shape[1] != n_shape or not np.isfinite(alpha).all():
        raise ValueError("volume_gps: shape_alpha must be finite numbers, 3 per design")
    return low, span, lengths, alpha


def volume_gps_from_dict(d: dict) -> VolumeGPs:
    volume = VolumeGPs(vector_gp_from_dict(d["gp"]), *shape_scaling(d))
    x = volume.gp.gps[0].x
    if (len(volume.shape_alpha) != len(x)
            or x.shape[1] != len(volume.pressure_lengths) + len(volume.shape_low)):
        raise ValueError("volume_gps: shape_alpha needs one row per fitted design and "
                         "pressure_lengths one per input before the shape")
    return volume


def fit_volume_gps(u: np.ndarray, volume_outputs: np.ndarray, pressure_gp: VectorGP,
                   seed: int = 0) -> VolumeGPs:
    """The volume GPs from the fitted designs' unit coordinates ``u`` (n, d), their volume
    outputs (n, 32; rise outputs) and the pressure GPs fitted to the same designs (their
    first 32 outputs the pressure nodes, one kernel: ``build.fit_curve_gps``): one GP per
    volume output, each its own kernel, on the shape of the pressure GPs' leave-one-out
    means; the correction that turns a query's shape into that at the fitted designs."""
    u = np.asarray(u, float)
    n_p = len(ANGLE_NODES_DEG)
    log_p = pressure_gp.center[:n_p] + pressure_gp.scale[:n_p] * np.column_stack(
        [g.y for g in pressure_gp.gps[:n_p]])
    s_loo = pressure_shape(loo_pressure_means(pressure_gp, n_p))
    low = s_loo.min(0)
    span = np.maximum(s_loo.max(0) - low, 1e-6)
    scaled_loo = (s_loo - low) / span
    kernel = pressure_gp.gps[0]
    alpha = cho_solve((kernel.chol, True),
                      (pressure_shape(log_p) - low) / span - scaled_loo)
    gp = fit_output_gps(np.column_stack((u, scaled_loo)), volume_outputs, seed=seed)
    return VolumeGPs(gp, low, span, kernel.lengths.copy(), alpha)
