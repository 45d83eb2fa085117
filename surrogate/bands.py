"""Prediction bands: parameter uncertainty (delta method) plus residual scatter.

The model's own scatter around the FE curves grows with the angle and vanishes at zero
pressure (both the FE and the model give angle 0 there), so its variance is modelled as
``residual_sd^2 (1 - exp(-p / tau))^2 + (residual_rel * angle)^2`` and both numbers are
estimated by maximum likelihood from the fit's residuals. A band at ``level`` is
``prediction +- z sqrt(g C g^T + scatter)``, with g the model's gradient and C the
parameter covariance; z is the normal quantile.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.stats import norm

from solver.errors import InputError


def z_value(level: float) -> float:
    """Two-sided normal quantile for a band at ``level`` (e.g. 1.96 at 0.95)."""
    if not isinstance(level, (int, float)) or not 0.5 <= level < 1.0:
        raise InputError("level", f"got {level!r}", "0.5 <= level < 1")
    return _z(float(level))


@lru_cache(maxsize=64)
def _z(level: float) -> float:
    return float(norm.ppf(0.5 + 0.5 * level))


def onset(x: np.ndarray) -> np.ndarray:
    """(1 - exp(-x))^2 with x = p / tau: the absolute scatter's growth from p = 0."""
    return np.expm1(-np.asarray(x, dtype=float)) ** 2


def scatter_variance(sd_abs: float, rel: float, prediction: np.ndarray,
                     x: np.ndarray) -> np.ndarray:
    """Variance of the model's residual scatter at the predicted values, x = p / tau."""
    return sd_abs * sd_abs * onset(x) + (rel * np.asarray(prediction)) ** 2


def parameter_variance(gradient: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """g C g^T for every row of ``gradient`` (..., k)."""
    return np.sum((gradient @ covariance) * gradient, axis=-1)


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
