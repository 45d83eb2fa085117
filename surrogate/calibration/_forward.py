"""The augmented model: the baseline plus effects, evaluated at every observation.

``angle_model(obs, families, values)``: ``families`` is an (n_families, 4) array of
(a_deg_per_mm, a_t_pa, b_t_per_mm, c); ``values`` maps effect parameter names (see
_effects.py) to numbers; an absent name means the effect is off.
"""

from __future__ import annotations

import numpy as np

from surrogate.calibration._data import Observations
from surrogate.exponential.equations import angle_from_constants, tau_from_constants

LAG_SUBSTEPS = 4


def chamber_pressure_pa(pressure_pa, flow_ul_s, values: dict[str, float]):
    """Gauge pressure minus the offset and the inlet's R Q drop."""
    p = np.asarray(pressure_pa, dtype=float) - values.get("p0_pa", 0.0)
    if "R_pa_per_ul_s" in values:
        p = p - values["R_pa_per_ul_s"] * np.asarray(flow_ul_s, dtype=float)
    return p


def static_angle_deg(p_chamber, L_mm, t_mm, fam: np.ndarray, values: dict[str, float]):
    """Quasi-static angle (deg): baseline with the tau, saturation and reverse terms;
    ``fam`` is (..., 4) family parameters broadcast to the points."""
    t_eff = np.asarray(t_mm, dtype=float) + values.get("dt_mm", 0.0)
    tau = values.get("s", 1.0) * tau_from_constants(fam[..., 1], fam[..., 2],
                                                    np.maximum(t_eff, 1e-6))
    tau = np.where(tau > 1.0, tau, 1.0)  # b_t t <= 1 has no meaning; keep the fit finite
    forward = angle_from_constants(fam[..., 0] * L_mm, tau, p_chamber, fam[..., 3])
    inv_max = values.get("inv_theta_max_per_deg", 0.0)
    if inv_max > 0.0:
        forward = np.tanh(forward * inv_max) / inv_max
    depth = values.get("depth_deg", 0.0)
    if depth != 0.0:
        q = np.maximum(p_chamber, 0.0) / values.get("p_r_pa", 200.0)
        forward = forward - depth * q * np.exp(1.0 - q)
    return forward


def angle_model(obs: Observations, families: np.ndarray, values: dict[str, float]
                ) -> np.ndarray:
    """Predicted angle (deg) at every observation of ``obs``."""
    fam = families[obs.family]
    tau_v = values.get("tau_v_s", 0.0)
    if tau_v > 0.0 and obs.has_time:
        out = _lagged(obs, fam, values, tau_v)
    else:
        p = chamber_pressure_pa(obs.pressure_pa, obs.flow_ul_s, values)
        out = static_angle_deg(p, obs.L_mm, obs.t_mm, fam, values)
    return out + values.get("offset_deg", 0.0)


def _lagged(obs: Observations, fam: np.ndarray, values: dict[str, float], tau_v: float
            ) -> np.ndarray:
    """First-order lag along each curve, exact for an input linear between substeps."""
    order = obs.padded_order()
    valid = order >= 0
    idx = np.where(valid, order, order[:, :1])
    t = obs.time_s[idx]
    p = chamber_pressure_pa(obs.pressure_pa[idx], obs.flow_ul_s[idx], values)
    L, th, f = obs.L_mm[idx], obs.t_mm[idx], fam[idx]
    n_curves, m = idx.shape
    w = (np.arange(1, LAG_SUBSTEPS + 1) / LAG_SUBSTEPS)[None, :]
    y = static_angle_deg(p[:, 0], L[:, 0], th[:, 0], f[:, 0], values)
    u_prev = y
    result = np.empty((n_curves, m))
    result[:, 0] = y
    for j in range(1, m):
        dt = (t[:, j] - t[:, j - 1])[:, None] / LAG_SUBSTEPS
        ps = p[:, j - 1, None] + w * (p[:, j] - p[:, j - 1])[:, None]
        us = static_angle_deg(ps, L[:, j, None], th[:, j, None], f[:, j, None, :], values)
        e = np.exp(-dt / tau_v)
        g = tau_v / dt * (1.0 - e)  # exact response to a ramp over one substep
        for k in range(LAG_SUBSTEPS):
            u = us[:, k]
            y = u - (u - u_prev) * g[:, 0] + (y - u_prev) * e[:, 0]
            u_prev = u
        result[:, j] = y
    out = np.empty(obs.n)
    out[order[valid]] = result[valid]
    return out
