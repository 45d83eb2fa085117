"""The emulator's bands calibrated on cross-validated database curves: one sd multiplier
per output node.

Each fold of the database (``cross_validated``: CV_FOLDS folds, designs sharing a
geometry in one) is predicted by the GPs refitted without it; per angle bin
(ANGLE_BINS_DEG, deg) the smallest multiplier whose held-out bands cover the target share
of the FE points in the bin (``cv_band_target``, ``node_band_scales``), for the band by
pressure (log p nodes) and by injected volume (log V nodes), never below MIN_BAND_SCALE
(the GP's own sd) nor above MAX_BAND_SCALE.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from surrogate.band_level import z_value
from surrogate.emulator.database_rows import LIMIT_ANGLE_DEG
from surrogate.emulator.features import ANGLE_NODES_DEG, N_NODES
from surrogate.emulator.node_curves import (
    ANGLES0,
    _monotone,
    _with_origin,
    floored_band,
    node_curves,
)
from surrogate.emulator.volume_curve import volume_shape

ANGLE_BINS_DEG = (0.0, 10.0, 20.0, 40.0, 60.0, 75.0, 90.0)   # band calibration bins
MIN_BAND_SCALE = 1.0              # band multipliers: never below the GP's own sd
MAX_BAND_SCALE = 50.0             # ... nor above this
CV_FOLDS = 5                      # band calibration: K-fold cross-validation
GEOMETRY_COORDINATES = 5          # the first five unit-cube coordinates: L, t, T, b, h


def cross_validated(u: np.ndarray, y: np.ndarray, seed: int = 0, folds: int = CV_FOLDS, *,
                    fit: Callable) -> tuple[np.ndarray, np.ndarray]:
    """K-fold cross-validated mean and variance of every output at every design: each
    fold predicted by the GPs ``fit`` returns (``fit(u, y, seed=seed)``: the curve GPs,
    ``build.fit_curve_gps``, or the force GPs, ``force_gps.fit_force_nodewise``) refitted,
    hyperparameters too, without it.
    Designs that share a geometry (the two PDMS bodies of a pooled group at one Sobol
    point) fall in one fold.

    Why not the closed-form leave-one-out: with the hyperparameters fitted to every
    design, and a PDMS twin left in, its bands (calibrated to cover 95 %) covered
    0.72 of the points of 15 held-out random FE designs."""
    geometry = np.round(u[:, :GEOMETRY_COORDINATES], 6)
    _, which = np.unique(geometry, axis=0, return_inverse=True)
    which = np.asarray(which).ravel()
    order = np.random.default_rng(seed).permutation(which.max() + 1)
    fold = (order % folds)[which]
    mean, var = np.empty_like(y), np.empty_like(y)
    for k in range(folds):
        test = fold == k
        if not test.any():
            continue
        gp = fit(u[~test], y[~test], seed=seed)
        mean[test], var[test] = gp.predict_many(u[test])
    return mean, var


def held_out_curves(curves: list, mean: np.ndarray, var: np.ndarray, scales: np.ndarray,
                    z: float, axis: str = "pressure"
                    ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Per database curve: its FE angles (deg, up to the FE's stop, signed positive) and
    the held-out (cross-validated) emulator's angle, band lower and upper (with the
    query's floor, ``emulator.floored_band``) at the curve's own pressures (``axis``
    "pressure": the log p nodes) or injected volumes ("volume": the log V nodes), from the
    held-out node means and variances."""
    half = slice(0, N_NODES) if axis == "pressure" else slice(N_NODES, 2 * N_NODES)
    out = []
    for i, (p_red, v_red, a) in enumerate(curves):
        sign = 1.0 if a[np.argmax(np.abs(a))] >= 0 else -1.0
        keep = np.abs(a) <= LIMIT_ANGLE_DEG
        y, sd = mean[i, half], np.sqrt(var[i, half]) * scales[half]
        shape = _monotone if axis == "pressure" else volume_shape
        xm, xl, xu = (_with_origin(shape(c)) for c in node_curves(y, sd, z))
        q = (p_red if axis == "pressure" else v_red)[keep]
        angle = np.interp(q, xm, ANGLES0)
        lower, upper = floored_band(angle, np.interp(q, xu, ANGLES0), np.interp(q, xl, ANGLES0))
        out.append((sign * a[keep], angle, lower, upper))
    return out


def angle_bin(angle_deg: np.ndarray) -> np.ndarray:
    """Index of the ANGLE_BINS_DEG bin of each angle (the last bin closed)."""
    edges = np.asarray(ANGLE_BINS_DEG)
    return np.clip(np.searchsorted(edges, angle_deg, side="right") - 1, 0, len(edges) - 2)


def cv_band_target(level: float) -> float:
    """The cross-validated coverage each angle bin's band multiplier aims at for a
    ``level`` band: 1 - (1 - level) / 5 (0.99 for 95 %; the bisection reaches 0.965-0.98
    overall on the shipped database). The folds leave out Sobol points of the database's
    own reduced box; random designs drawn uniformly in the whole box (each layer's
    stiffness scaled on its own) sit further from the database: bands calibrated to 95 %
    in cross-validation covered 0.92 of 22 held-out FE curves' points, to 97.5 % also
    0.92, to 99 % 0.94 (benchmarks/RESULTS.md)."""
    return 1.0 - (1.0 - level) / 5.0


def node_band_scales(curves: list, mean: np.ndarray, var: np.ndarray, level: float
                     ) -> np.ndarray:
    """The sd multiplier of every output node (log p, then log V, at each angle node).

    ``mean`` and ``var`` are held-out predictions at the database designs
    (``cross_validated``). Pressure nodes: one multiplier per angle bin
    (ANGLE_BINS_DEG), the smallest whose held-out bands cover ``level`` of the FE points
    with angles in that bin
    (bisection, bins from low angles up, two sweeps). One multiplier for the whole curve was set by
    the low-angle points, where the FE steps crowd (half the points lie below 10 deg) and
    the GP's sd is smallest relative to its error: above 10 deg those bands covered every
    held-out point and were +-30 deg wide. Volume nodes: the same, for the band by
    injected volume at the curves' own FE volumes.
    All kept within [MIN_BAND_SCALE, 50]: a band is never narrower than the GP's own
    predictive sd. Cross-validation alone put the multipliers above 10 deg at 0.5-0.8,
    and such bands covered only 0.72 of the points of 15 held-out random FE designs
    (benchmarks/RESULTS.md); at 1.0 those covered 0.97-1.0 above 20 deg."""
    z = z_value(level)
    node_bin = angle_bin(ANGLE_NODES_DEG)
    scales = np.ones(2 * N_NODES)
    for axis, offset in (("pressure", 0), ("volume", N_NODES)):
        fe_bins = [angle_bin(fe) for fe, *_ in
                   held_out_curves(curves, mean, var, scales, z, axis)]
        # two sweeps: a bin's nodes also shape the band just outside it
        for b in list(range(len(ANGLE_BINS_DEG) - 1)) * 2:
            nodes = offset + np.flatnonzero(node_bin == b)
            lo_s, hi_s = MIN_BAND_SCALE, MAX_BAND_SCALE
            for _ in range(20):
                mid = np.sqrt(lo_s * hi_s)
                scales[nodes] = mid
                held = held_out_curves(curves, mean, var, scales, z, axis)
                if _bin_coverage(held, fe_bins, b) >= level:
                    hi_s = mid
                else:
                    lo_s = mid
            scales[nodes] = hi_s
    return np.clip(scales, MIN_BAND_SCALE, MAX_BAND_SCALE)


def inside_band(fe: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Which FE angles (deg) lie inside their band [lower, upper], 1e-9 deg of round-off
    allowed."""
    return (fe >= lower - 1e-9) & (fe <= upper + 1e-9)


def coverage(held: list) -> float:
    """Share of all held-out FE points inside their band."""
    return float(np.mean(np.concatenate([inside_band(fe, lo, hi) for fe, _, lo, hi in held])))


def _bin_coverage(held: list, fe_bins: list, b: int) -> float:
    """Share of the held-out FE points of angle bin ``b`` inside their band."""
    inside = total = 0
    for (fe, _, lo, hi), bins in zip(held, fe_bins):
        sel = bins == b
        inside += int(inside_band(fe[sel], lo[sel], hi[sel]).sum())
        total += int(sel.sum())
    return inside / total if total else 1.0
