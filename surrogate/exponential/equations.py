"""The exponential bending model and its extension, as pure vectorised functions.

Paper form ("exponential", Eq. 5-6 of the reference paper)::

    angle_deg = A (exp(x) - 1),  x = p / tau
    A   = a L                         (a: deg/mm, L: chamber length, mm)
    tau = a_t log10(b_t t)            (a_t: Pa, b_t: 1/mm, t: membrane thickness, mm)

Extended form ("extended"): one more dimensionless parameter c per family::

    angle_deg = A (exp(x + c x^2) - 1)

i.e. an effective pressure constant that changes with pressure, 1/tau_eff = (1 + c x)/tau.
It keeps the paper's linear small-pressure limit (angle ~ A p / tau) and bends the
large-angle end up (c > 0: the membrane softens as it balloons) or down (c < 0: the
Ogden material stiffens). c = 0 is the paper's form.

Every function broadcasts over L_mm, t_mm and pressure_pa; ``theta`` is the parameter
vector (a, a_t, b_t) or (a, a_t, b_t, c). A is signed: a < 0 for a family that bends the
other way (e.g. an Ecoflex body on a PDMS membrane).

Fit coordinates: the joint fit and its covariance use log10 b_t in place of b_t
(``to_fit``, ``from_fit``, ``gradient_to_fit``), tau = a_t (log10 b_t + log10 t). b_t is
badly scaled: when tau hardly depends on t, b_t = 10^(level / a_t) runs to 1e8-1e15 /mm
and d angle / d b_t to ~1e-15, below any pseudo-inverse cut-off, while log10 b_t stays
an ordinary parameter with a finite standard error.
"""

from __future__ import annotations

import numpy as np

FORMS = ("exponential", "extended")
PARAMETER_NAMES = {
    "exponential": ("a_deg_per_mm", "a_t_pa", "b_t_per_mm"),
    "extended": ("a_deg_per_mm", "a_t_pa", "b_t_per_mm", "c"),
}
FIT_NAMES = {form: names[:2] + ("log10_b_t_per_mm",) + names[3:]
             for form, names in PARAMETER_NAMES.items()}
TAU_FORM = "tau_pa = a_t_pa * log10(b_t_per_mm * t_mm)"
LN10 = float(np.log(10.0))
B_T = 2  # index of b_t in theta (of log10 b_t in the fit coordinates)


def to_fit(theta: np.ndarray) -> np.ndarray:
    """theta -> fit coordinates (b_t replaced by log10 b_t)."""
    q = np.array(theta, dtype=float)
    q[B_T] = np.log10(q[B_T])
    return q


def from_fit(q: np.ndarray) -> np.ndarray:
    """Fit coordinates -> theta (log10 b_t replaced by b_t)."""
    theta = np.array(q, dtype=float)
    theta[B_T] = 10.0 ** theta[B_T]
    return theta


def gradient_to_fit(gradient: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """d / d theta (..., k) -> d / d (fit coordinates): the b_t column times
    d b_t / d log10 b_t = b_t ln 10 (e.g. d angle / d log10 b_t = a_t d angle / d tau)."""
    g = np.array(gradient, dtype=float)
    g[..., B_T] *= float(theta[B_T]) * LN10
    return g


def covariance_from_b_t(cov: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """A covariance of theta (b_t in 1/mm) -> one of the fit coordinates (delta method,
    exact to first order: bands computed from either agree)."""
    d = np.ones(len(theta))
    d[B_T] = 1.0 / (float(theta[B_T]) * LN10)
    return np.asarray(cov, dtype=float) * np.outer(d, d)


def tau_from_constants(a_t_pa, b_t_per_mm, t_mm) -> np.ndarray:
    """Eq. 6 as this package reads it: tau (Pa) = a_t log10(b_t t); <= 0 when b_t t <= 1."""
    return a_t_pa * np.log10(b_t_per_mm * np.asarray(t_mm, dtype=float))


def angle_from_constants(A_deg, tau_pa_, pressure_pa, c=0.0) -> np.ndarray:
    """Eq. 5 (c = 0) and its extension: angle (deg) = A (exp(x + c x^2) - 1), x = p / tau,
    for a curve's own constants A (deg) and tau (Pa) at pressure p (Pa)."""
    return A_deg * np.expm1(_exponent(np.asarray(pressure_pa, dtype=float) / tau_pa_, c))


def _exponent(x, c) -> np.ndarray:
    return x + c * x * x if np.any(c) else x


def tau_pa(theta: np.ndarray, t_mm: np.ndarray | float) -> np.ndarray:
    """Pressure constant tau (Pa) for membrane thickness t (mm); <= 0 when b_t t <= 1."""
    return tau_from_constants(theta[1], theta[2], t_mm)


def amplitude_deg(theta: np.ndarray, L_mm: np.ndarray | float) -> np.ndarray:
    """Amplification constant A = a L (deg), signed."""
    return theta[0] * np.asarray(L_mm, dtype=float)


def _c(theta: np.ndarray) -> float:
    return float(theta[3]) if len(theta) > 3 else 0.0


def angle_deg(theta: np.ndarray, L_mm, t_mm, pressure_pa) -> np.ndarray:
    """Bending angle (deg) at cavity pressure p (Pa) for chamber length L and thickness t."""
    return angle_from_constants(amplitude_deg(theta, L_mm), tau_pa(theta, t_mm), pressure_pa,
                                _c(theta))


def length_mm(theta: np.ndarray, t_mm, pressure_pa, angle_magnitude_deg) -> np.ndarray:
    """Chamber length L (mm) whose |angle| at pressure p (Pa) is ``angle_magnitude_deg``
    (closed form, L = |angle| / (|a| (exp(x + c x^2) - 1))); NaN/inf where none does."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.abs(angle_magnitude_deg) / np.abs(
            angle_from_constants(float(theta[0]), tau_pa(theta, t_mm), pressure_pa, _c(theta)))


def angle_gradient(theta: np.ndarray, L_mm, t_mm, pressure_pa) -> np.ndarray:
    """d angle / d theta, shape broadcast(L, t, p) + (len(theta),)."""
    L = np.asarray(L_mm, dtype=float)
    t = np.asarray(t_mm, dtype=float)
    tau = tau_pa(theta, t)
    x = np.asarray(pressure_pa, dtype=float) / tau
    c = _c(theta)
    e = np.exp(x + c * x * x)
    A = theta[0] * L
    d_tau = -A * e * (1.0 + 2.0 * c * x) * x / tau  # d angle / d tau
    cols = [L * (e - 1.0), d_tau * np.log10(theta[2] * t), d_tau * theta[1] / (theta[2] * LN10)]
    if len(theta) > 3:
        cols.append(A * e * x * x)
    return np.stack(np.broadcast_arrays(*cols), axis=-1)


def pressure_pa(theta: np.ndarray, L_mm, t_mm, angle_deg_: np.ndarray | float) -> np.ndarray:
    """Inverse of ``angle_deg``: the pressure (Pa) that gives the angle (closed form),
    p = tau x with x + c x^2 = ln(1 + angle / A). NaN where the angle is not reachable
    (opposite sign to A, or beyond the extended model's maximum when c < 0)."""
    A = amplitude_deg(theta, L_mm)
    tau = tau_pa(theta, t_mm)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.asarray(angle_deg_, dtype=float) / A
        y = np.where(ratio >= 0.0, np.log1p(ratio), np.nan)
        x = _solve_exponent(y, _c(theta))
    return tau * x


def _solve_exponent(y: np.ndarray, c: float) -> np.ndarray:
    """Root x >= 0 of x + c x^2 = y (stable form 2y / (1 + sqrt(1 + 4 c y)))."""
    if not c:
        return y
    disc = 1.0 + 4.0 * c * y
    with np.errstate(invalid="ignore"):
        return np.where(disc >= 0.0, 2.0 * y / (1.0 + np.sqrt(disc)), np.nan)


def pressure_gradient(theta: np.ndarray, L_mm, t_mm, angle_deg_) -> tuple[np.ndarray, np.ndarray]:
    """(d p / d theta with shape (..., len(theta)), d p / d angle), for the inverse's band."""
    L = np.asarray(L_mm, dtype=float)
    t = np.asarray(t_mm, dtype=float)
    ang = np.asarray(angle_deg_, dtype=float)
    A = theta[0] * L
    tau = tau_pa(theta, t)
    c = _c(theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        y = np.log1p(ang / A)
        x = _solve_exponent(y, c)
        dx_dy = 1.0 / (1.0 + 2.0 * c * x)
        dy_dA = -ang / (A * (A + ang))
        cols = [tau * dx_dy * dy_dA * L, x * np.log10(theta[2] * t),
                x * theta[1] / (theta[2] * LN10)]
        if len(theta) > 3:
            cols.append(-tau * x * x * dx_dy)
        dp_dangle = tau * dx_dy / (A + ang)
    return np.stack(np.broadcast_arrays(*cols), axis=-1), dp_dangle


def max_angle_deg(theta: np.ndarray, L_mm, t_mm) -> np.ndarray:
    """Largest angle magnitude the model reaches (inf unless c < 0, where the exponent
    x + c x^2 peaks at x = -1 / (2 c))."""
    c = _c(theta)
    A = amplitude_deg(theta, L_mm) + 0.0 * np.asarray(t_mm, dtype=float)
    if c >= 0.0:
        return np.full(np.shape(A), np.inf)
    return np.abs(A * np.expm1(-1.0 / (4.0 * c)))
