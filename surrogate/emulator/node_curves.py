"""The emulated curves on FINE_ANGLES_DEG, read off a design's node values.

The emulator's GPs give a design's node vector (``features``: log(p_k / theta_k) and
log(V_k / theta_k) at ANGLE_NODES_DEG); a query draws p(theta) (Pa, reduced) and V(theta)
(ul, reduced) through those nodes on the fine angles (a natural spline), the band's low
and high curves at -+ z sd (the half-width linear between nodes), and reads angles off
them with the origin (0 deg at 0 Pa, 0 ul) prepended (ANGLES0).
"""

from __future__ import annotations

import numpy as np

from surrogate.emulator.features import (
    ANGLE_BAND_FLOOR_DEG,
    ANGLE_NODES_DEG,
    FINE_ANGLES_DEG,
    N_NODES,
    linear_matrix,
    spline_matrix,
)

_B_ANGLE = spline_matrix(ANGLE_NODES_DEG, FINE_ANGLES_DEG)
_L_ANGLE = linear_matrix(ANGLE_NODES_DEG, FINE_ANGLES_DEG)


def node_curves(y: np.ndarray, sd: np.ndarray, z: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """p(theta) (or V(theta)) on FINE_ANGLES_DEG from node values ``y`` = log(x / theta)
    and their sd (rows of a 2-D ``y`` are designs): the mean through the natural spline,
    the band's low and high curves at -+ z sd with the half-width linear between nodes
    (a spline of the half-width overshoots where the band multiplier changes between
    angle bins, and the band would cross the mean). Not yet made monotone."""
    theta = FINE_ANGLES_DEG
    centre = y @ _B_ANGLE.T
    half = z * (sd @ _L_ANGLE.T)
    return (theta * np.exp(centre), theta * np.exp(centre - half),
            theta * np.exp(centre + half))


def free_angles_deg(node_mean: np.ndarray, p_red: np.ndarray) -> np.ndarray:
    """|theta| (deg) of the emulated free tip at reduced pressures ``p_red`` (Pa), one row
    per row of ``node_mean`` (emulated node vectors, log(p_k / theta_k) first), read off
    the monotone p(theta) as a query reads it; NaN past the curve's last angle (90 deg)."""
    y = np.atleast_2d(node_mean)[:, :N_NODES]
    curves = np.maximum.accumulate(node_curves(y, np.zeros_like(y), 0.0)[0], axis=1)
    q = np.asarray(p_red, float)
    out = np.array([np.interp(q, _with_origin(c), ANGLES0) for c in curves])
    out[q[None, :] > curves[:, -1:] * (1 + 1e-12)] = np.nan
    return out


def floored_band(angle: np.ndarray, lower: np.ndarray, upper: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The band (lower, upper) widened to at least ANGLE_BAND_FLOOR_DEG either side of
    ``angle`` (deg; NaN stays NaN)."""
    return (np.fmin(lower, angle - ANGLE_BAND_FLOOR_DEG),
            np.fmax(upper, angle + ANGLE_BAND_FLOOR_DEG))


def _monotone(p: np.ndarray) -> np.ndarray:
    return np.maximum.accumulate(p)


def _with_origin(x: np.ndarray) -> np.ndarray:
    return np.concatenate(([0.0], x))


ANGLES0 = _with_origin(FINE_ANGLES_DEG)
