"""Prediction bands: parameter uncertainty (delta method) plus residual scatter.

The model's own scatter around the FE curves grows with the angle and vanishes at zero
pressure (both the FE and the model give angle 0 there), so its variance is modelled as
``residual_sd^2 (1 - exp(-p / tau))^2 + (residual_rel * angle)^2`` and both numbers are
estimated by maximum likelihood from the fit's residuals. A band at ``level`` is
``prediction +- z sqrt(g C g^T + scatter)``, with g the model's gradient and C the
parameter covariance; z is the normal quantile. The inverse's band (pressure for an
angle) is the delta method on p plus the scatter carried through dp/dangle. Every
forward and inverse band of the exponential model is computed here (``angle_band``,
``pressure_band``).
"""

from __future__ import annotations

import math

import numpy as np

from surrogate.band_level import z_value
from surrogate.exponential import equations
from surrogate.exponential.parameters import ModelParameters


def onset(x: np.ndarray) -> np.ndarray:
    """(1 - exp(-x))^2 with x = p / tau: the absolute scatter's growth from p = 0."""
    return np.expm1(-np.asarray(x, dtype=float)) ** 2


def scatter_variance(sd_abs: float, rel: float, prediction: np.ndarray,
                     x: np.ndarray) -> np.ndarray:
    """Variance of the model's residual scatter at the predicted values, x = p / tau."""
    return sd_abs * sd_abs * onset(x) + (rel * np.asarray(prediction)) ** 2


def fit_scatter(residuals: np.ndarray, prediction: np.ndarray,
                x: np.ndarray) -> tuple[float, float]:
    """Maximum-likelihood (sd_abs, rel) of zero-mean normal residuals whose variance is
    sd_abs^2 (onset(x) + (rho * prediction)^2), rel = rho * sd_abs: for each rho of a log
    grid the best sd_abs is closed-form, and the rho with the largest likelihood wins."""
    r2 = np.asarray(residuals, dtype=float) ** 2
    m2 = np.asarray(prediction, dtype=float) ** 2
    scale = math.sqrt(max(float(m2.max(initial=0.0)), 1e-12))
    rho = np.concatenate([[0.0], np.geomspace(1e-3, 1e4, 211) / scale])
    shape = np.maximum(onset(x), 1e-12) + np.outer(rho * rho, m2)   # (n_rho, n)
    s2 = np.maximum(np.mean(r2 / shape, axis=1), (1e-6 * scale) ** 2)
    nll = np.sum(np.log(shape), axis=1) + r2.size * np.log(s2) + np.sum(r2 / shape, axis=1) / s2
    best = int(np.argmin(nll))
    sd_abs = math.sqrt(float(s2[best]))
    return sd_abs, float(rho[best] * sd_abs)


def angle_band(params: ModelParameters, L_mm, t_mm, pressure_pa, level: float = 0.95,
         scale: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(angle or force, lower, upper) at pressure p (Pa) and ``level``, in the
    parameters' unit (deg, or mN for a force model); ``scale`` multiplies the half-width."""
    z = z_value(level)
    m = equations.angle_deg(params.theta, L_mm, t_mm, pressure_pa)
    g = equations.angle_gradient(params.theta, L_mm, t_mm, pressure_pa)
    x = np.asarray(pressure_pa, dtype=float) / equations.tau_pa(params.theta, t_mm)
    var = params.parameter_variance(g) + scatter_variance(
        params.residual_sd, params.residual_rel, m, x)
    half = scale * params.band_scale * z * np.sqrt(var)
    return m, m - half, m + half

def pressure_band(params: ModelParameters, L_mm, t_mm, angle_deg, level: float = 0.95
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(pressure_pa, half-width in Pa) giving each angle (deg) at ``level``: closed-form
    inverse p = tau x, x + c x^2 = ln(1 + angle / A) (NaN where not reachable), band by
    the delta method on p plus the scatter carried through dp/dangle (0 at angle 0)."""
    ang = np.asarray(angle_deg, dtype=float)
    p = equations.pressure_pa(params.theta, L_mm, t_mm, ang)
    g, dp_da = equations.pressure_gradient(params.theta, L_mm, t_mm, ang)
    x = p / equations.tau_pa(params.theta, t_mm)
    var = (params.parameter_variance(g)
           + dp_da**2 * scatter_variance(params.residual_sd, params.residual_rel, ang, x))
    half = params.band_scale * z_value(level) * np.sqrt(np.where(ang == 0.0, 0.0, var))
    return p, half
