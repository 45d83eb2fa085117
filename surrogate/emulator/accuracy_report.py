"""The emulator's accuracy report: cross-validated angle errors (deg) and band coverage
of the database curves, overall, by angle bin and by injected volume, and apart for the
curves near an early-ended one (within NEAR_FAILED_RADIUS in the unit cube)."""

from __future__ import annotations

import numpy as np

from surrogate.band_level import z_value
from surrogate.emulator.band_scales import (
    ANGLE_BINS_DEG,
    angle_bin,
    coverage,
    held_out_curves,
    inside_band,
)
from surrogate.emulator.features import N_NODES
from surrogate.emulator.pair_emulator import NEAR_FAILED_RADIUS, nearest_distance


def near_failed_mask(u: np.ndarray, failed: list) -> np.ndarray:
    """Which designs (rows of ``u``, unit cube) lie within NEAR_FAILED_RADIUS of an
    early-ended curve of ``failed`` ((u, end angle, reason) tuples), as a query there
    would be flagged (``near_early_ended_fe_curves``)."""
    points = np.array([np.asarray(f[0], float) for f in failed]) if failed else None
    return nearest_distance(u, points) < NEAR_FAILED_RADIUS


def cv_angle_report(curves: list, mean: np.ndarray, var: np.ndarray,
                      scales: np.ndarray, level: float) -> dict:
    """Cross-validated angle errors (deg) and band coverage, overall and by angle bin:
    each database curve predicted by the emulator fitted without its fold, at the
    curve's own pressures."""
    held = held_out_curves(curves, mean, var, scales, z_value(level))
    errors = [m - fe for fe, m, _, _ in held]
    flat = np.concatenate(errors)
    ins = np.concatenate([inside_band(fe, lo, hi) for fe, _, lo, hi in held])
    bins = angle_bin(np.concatenate([fe for fe, *_ in held]))
    by_bin = []
    for b, (a0, a1) in enumerate(zip(ANGLE_BINS_DEG[:-1], ANGLE_BINS_DEG[1:])):
        sel = bins == b
        if sel.any():
            by_bin.append({"from_deg": a0, "to_deg": a1, "points": int(sel.sum()),
                           "coverage": float(ins[sel].mean()),
                           "rmse_deg": float(np.sqrt(np.mean(flat[sel] ** 2)))})
    return {"cv_rmse_deg": float(np.sqrt(np.mean(flat**2))),
            "cv_max_deg": float(np.max(np.abs(flat))),
            "cv_curve_rmse_deg": [float(np.sqrt(np.mean(e**2))) for e in errors],
            "cv_coverage": float(ins.mean()), "cv_coverage_by_angle": by_bin,
            "cv_coverage_by_volume": coverage(held_out_curves(curves, mean, var, scales,
                                                               z_value(level), "volume")),
            "band_scale_median": float(np.median(scales[:N_NODES])),
            "band_scale_range": [float(scales.min()), float(scales.max())]}


def near_failed_report(curves: list, mean: np.ndarray, var: np.ndarray,
                        band_scale: np.ndarray, near: np.ndarray, level: float) -> dict:
    """Cross-validated angle RMSE and band coverage of the curves near an early-ended one
    and of the others, by pressure (the random designs' calibration,
    ``random_calibration``, widens the bands of the near ones)."""
    z = z_value(level)
    out: dict = {"curves": int(near.sum()), "far_curves": int((~near).sum())}
    for name, sel in (("far", ~near), ("near", near)):
        idx = np.flatnonzero(sel)
        if not len(idx):
            continue
        held = held_out_curves([curves[i] for i in idx], mean[idx], var[idx], band_scale, z)
        out[f"{name}_cv_coverage"] = coverage(held)
        out[f"{name}_cv_rmse_deg"] = float(np.sqrt(np.mean(np.concatenate(
            [(m - fe) ** 2 for fe, m, _, _ in held]))))
    return out
