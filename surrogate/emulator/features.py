"""An FE curve as a fixed-length vector, and back.

A free-tip curve is read as chamber pressure and injected volume at fixed bending angles
(``ANGLE_NODES_DEG``), on its rising branch (angle and pressure both increasing, i.e. up
to a pressure maximum if there is one). The vector is

    y = (log(p_k / theta_k), log(V_k / theta_k))   k over the nodes reached

(secant stiffness and secant volume per degree: both finite at theta -> 0 and smooth).
Values between FE points come from monotone cubic (PCHIP) interpolation in
(log theta, log p) and (log theta, log V), so a power-law stretch of the curve is exact.

A blocked-tip curve is read as force per pressure at fixed pressures
(``FORCE_PRESSURE_NODES_PA``, to 2500 Pa where nearly every blocked FE curve converges):
y = F_j / p_j in mN/kPa, signed (the small initial reaction can change sign). The emulator
interpolates it normalised by the free tip's secant compliance at the first angle node,
s0 = theta / p (deg/Pa, signed; from the free-curve emulator, which has ~10x as many
designs): for a linear cantilever the blocked-tip force is the free tip's deflection over
the tip's compliance, F ~ 1.5 EI theta / L^2, so (F/p) / s0 varies over the box as EI / L^2
does (smoothly, in log lengths: the GP's linear mean), not with the chamber's whole
response. The GP sees ``force_feature`` = asinh((F/p) / (s0 x FORCE_RATIO_UNIT)): a log
of the ratio where it is large, linear through zero where the initial reaction changes
sign, so that the band is relative to the force (leave-one-design-out, shipped data:
F/p's median relative error 8-12 % where the raw F/p gave bands wider than the force).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline, PchipInterpolator

ANGLE_NODES_DEG = np.array([0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.5,
                            8.0, 10.0, 12.5, 15.0, 18.0, 21.0, 25.0, 30.0, 35.0, 40.0,
                            45.0, 50.0, 55.0, 60.0,
                            65.0, 70.0, 75.0, 80.0, 85.0, 90.0])
N_NODES = len(ANGLE_NODES_DEG)   # a curve's nodes: N_NODES pressure, then N_NODES volume outputs

# The band is never narrower than this either side of the answer. A band that is a
# multiple of the GP's sd in log(p / theta) is relative; at the first steps of curves
# near the Ecoflex/Ecoflex stiffness balance the FE angle is a few thousandths of a
# degree (some of the other sign), and covering those relatively took a multiplier of
# 21-50 below 10 deg (2.8 with this floor). Carried up the curve by its monotone envelope,
# that made the group's bands run from 0 to twice the angle at 60 deg. Half the 0.1 deg a
# camera reading resolves; the calibration (band_scales.node_band_scales) counts with it.
ANGLE_BAND_FLOOR_DEG = 0.05

FORCE_PRESSURE_NODES_PA = np.array([25.0, 50.0, 100.0, 200.0, 300.0, 400.0, 500.0, 750.0,
                                    1000.0, 1250.0, 1500.0, 1750.0, 2000.0, 2500.0])
FINE_ANGLES_DEG = np.concatenate((np.linspace(0.01, 0.5, 50),
                                  np.linspace(0.5, 90.0, 359)[1:]))


@dataclass(frozen=True)
class CurveFeatures:
    """One free-tip FE curve as node values (NaN past the rising branch).

    sign              +1 bends away from the membrane, -1 towards it
    log_p, log_v      log(p_k / theta_k), log(V_k / theta_k) per node (Pa/deg, ul/deg)
    end_angle_deg     last angle of the rising branch (|angle|)
    end_pressure_pa   its pressure
    last_step_from_deg  the angle the FE's last step on it started from (|angle|; 0 with
                      fewer than two points)
    """

    sign: float
    log_p: np.ndarray
    log_v: np.ndarray
    end_angle_deg: float
    end_pressure_pa: float
    last_step_from_deg: float = 0.0


def bending_sign(angle_deg: np.ndarray) -> float:
    """+1 or -1: the sign of the curve's largest-magnitude angle."""
    a = np.asarray(angle_deg, float)
    return 1.0 if a[int(np.argmax(np.abs(a)))] >= 0 else -1.0


def rising_branch(pressure_pa: np.ndarray, angle_deg: np.ndarray) -> tuple[int, int]:
    """(start, stop): the points on which sign x angle is positive and it and the pressure
    both increase. ``start`` skips a small initial bend the other way (a coarse-mesh
    artefact near p = 0, docs/verification.md); ``stop`` is a pressure maximum or the
    curve's end."""
    a = bending_sign(angle_deg) * np.asarray(angle_deg, float)
    p = np.asarray(pressure_pa, float)
    start = 1
    while start < len(a) and a[start] <= 0:
        start += 1
    n = min(start + 1, len(a))
    while n < len(a) and a[n] > a[n - 1] and p[n] > p[n - 1]:
        n += 1
    return start, n


def curve_features(pressure_pa: np.ndarray, volume_ul: np.ndarray,
                   angle_deg: np.ndarray) -> CurveFeatures:
    """Node values of one curve (see the module docstring)."""
    p = np.asarray(pressure_pa, float)
    v = np.asarray(volume_ul, float)
    a = np.asarray(angle_deg, float)
    start, n = rising_branch(p, a)
    sign = bending_sign(a)
    a_abs, p, v = sign * a[start:n], p[start:n], v[start:n]
    keep = (a_abs > 1e-6) & (p > 0) & (v > 0)
    la, lp, lv = np.log(a_abs[keep]), np.log(p[keep]), np.log(v[keep])
    log_p = np.full(len(ANGLE_NODES_DEG), np.nan)
    log_v = np.full(len(ANGLE_NODES_DEG), np.nan)
    if len(la) >= 2:
        end = float(a_abs[keep][-1])
        nodes = ANGLE_NODES_DEG <= end + 1e-9
        ln = np.log(ANGLE_NODES_DEG[nodes])
        # below the first FE point: the linear regime, p and V proportional to the angle
        ln_c = np.maximum(ln, la[0])
        lp_n = PchipInterpolator(la, lp)(ln_c) + np.where(ln < la[0], ln - la[0], 0.0)
        lv_n = PchipInterpolator(la, lv)(ln_c) + np.where(ln < la[0], ln - la[0], 0.0)
        log_p[nodes] = lp_n - ln
        log_v[nodes] = lv_n - ln
    end_angle, end_pressure = (float(a_abs[-1]), float(p[-1])) if len(a_abs) else (0.0, 0.0)
    step_from = float(a_abs[-2]) if len(a_abs) >= 2 else 0.0
    return CurveFeatures(sign, log_p, log_v, end_angle, end_pressure, step_from)


def force_features(pressure_pa: np.ndarray, force_mn: np.ndarray) -> np.ndarray:
    """F / p (mN/kPa, signed) at FORCE_PRESSURE_NODES_PA, NaN beyond the curve's end;
    linear interpolation between FE points (F is smooth and nearly linear in p)."""
    p = np.asarray(pressure_pa, float)
    f = np.asarray(force_mn, float)
    n = 1
    while n < len(p) and p[n] > p[n - 1] and np.isfinite(f[n]):
        n += 1
    out = np.full(len(FORCE_PRESSURE_NODES_PA), np.nan)
    if n >= 2:
        nodes = FORCE_PRESSURE_NODES_PA <= p[n - 1] * (1 + 1e-9)
        q = FORCE_PRESSURE_NODES_PA[nodes]
        out[nodes] = np.interp(q, p[:n], f[:n]) / (q / 1000.0)
    return out


FORCE_RATIO_UNIT = 1.0    # (mN/kPa) / (deg/Pa): where asinh turns from linear to log


def free_secant_deg_per_pa(node_mean: np.ndarray, sign: float) -> np.ndarray:
    """theta / p (deg/Pa, signed) at the first angle node from the emulated free-curve
    vector(s) (``log(p_k / theta_k)`` first), the linear-regime compliance of the free tip."""
    return sign * np.exp(-np.asarray(node_mean, float)[..., 0])


def force_feature(per_kpa: np.ndarray, secant_deg_per_pa: np.ndarray | float) -> np.ndarray:
    """The interpolated force variable: asinh((F/p) / (s0 x FORCE_RATIO_UNIT))."""
    s0 = np.asarray(secant_deg_per_pa, float)
    s0 = s0[..., None] if s0.ndim else s0
    return np.arcsinh(np.asarray(per_kpa, float) / (s0 * FORCE_RATIO_UNIT))


def per_kpa_from_feature(feature: np.ndarray, secant_deg_per_pa: np.ndarray | float
                         ) -> np.ndarray:
    """F/p (mN/kPa) back from ``force_feature`` (monotone in it for a given s0)."""
    s0 = np.asarray(secant_deg_per_pa, float)
    s0 = s0[..., None] if s0.ndim else s0
    return np.sinh(np.asarray(feature, float)) * s0 * FORCE_RATIO_UNIT


def between_force_nodes(values: np.ndarray, pressure_pa: np.ndarray | float) -> np.ndarray:
    """A force variable given at the first n of FORCE_PRESSURE_NODES_PA (``values`` (n,),
    or rows (m, n) read alike), read at ``pressure_pa`` (Pa): the natural cubic spline
    through the nodes in log p, sampled on a fixed fine grid (``FORCE_FINE_PER_INTERVAL``
    points per interval, the nodes among them) and read linearly between its points; the
    first node's value below it (the linear regime), the last's above.

    Why not linear between the nodes: the blocked tip's force is this variable times a
    smooth free-tip angle, so a linear variable put a corner at every node into the force
    curve (at L 9, t 0.5 mm its slope fell 28 % across 1750 Pa, a kink a user saw in the
    plot by volume). The spline is one fixed matrix product (its cost is lost in a
    query's noise, where a monotone cubic's slopes, computed per design, cost 8 % of a
    design's first query); in log p, as the nodes are spaced, it follows the database's
    curves as closely (benchmarks/RESULTS.md, forty-ninth session)."""
    y = np.asarray(values, float)
    grid, matrix = _force_spline(y.shape[-1])
    fine = y @ matrix
    x = np.asarray(pressure_pa, float)
    if fine.ndim == 1:
        return np.interp(x, grid, fine)
    return np.stack([np.interp(x, grid, row) for row in fine.reshape(-1, len(grid))]
                    ).reshape(fine.shape[:-1] + x.shape)


FORCE_FINE_PER_INTERVAL = 32


@functools.cache
def _force_spline(n: int) -> tuple[np.ndarray, np.ndarray]:
    """For the first n force nodes: the fine grid up to the n-th (Pa, log-spaced within
    each interval, the nodes exact) and the matrix (n, grid) taking node values to the
    natural spline's there (``spline_matrix``); n = 1: the one value everywhere. Made at
    a group's first force answer, not at import."""
    q, k = FORCE_PRESSURE_NODES_PA, FORCE_FINE_PER_INTERVAL
    if n == 1:
        return q[:1], np.ones((1, 1))
    grid = np.exp(np.concatenate([np.linspace(np.log(a), np.log(b), k + 1)[:-1]
                                  for a, b in zip(q[:n - 1], q[1:n], strict=True)]
                                 + [np.log(q[n - 1:n])]))
    grid[::k] = q[:n]
    return grid, np.ascontiguousarray(spline_matrix(q[:n], grid).T)


def force_at(per_kpa: np.ndarray, pressure_pa: np.ndarray | float) -> np.ndarray:
    """Blocked-tip force (mN) at ``pressure_pa`` (Pa) from F/p values (mN/kPa) at the first
    ``len(per_kpa)`` of FORCE_PRESSURE_NODES_PA: F = p x (F/p), F/p between the nodes as
    ``between_force_nodes`` reads it (constant below the first: the linear regime)."""
    q = np.asarray(pressure_pa, float)
    return q / 1000.0 * between_force_nodes(per_kpa, q)


# The blocked tip's force over the free tip's angle at the same pressure (mN/deg, reduced:
# the membrane at its preset, W = 3 mm): where asinh of it turns from linear to log. The
# ratio is 1e-3-3e-2 mN/deg from 50 Pa on and crosses zero only at the first node (25 Pa),
# where the blocked tip's small initial reaction can have the other sign.
FORCE_ANGLE_UNIT = 2e-4


def force_angle_feature(force_mn: np.ndarray, angle_deg: np.ndarray) -> np.ndarray:
    """The force variable of ``angle_ratio`` emulators: asinh((F / theta) / FORCE_ANGLE_UNIT),
    F the blocked tip's force (mN) and theta the free tip's angle (deg, same sign
    convention) at the same pressure; NaN where theta is 0 or either is not finite.

    Why: for a cantilever the blocked tip's force is the free tip's deflection over the
    tip's compliance, F ~ 1.5 EI theta / L^2. Along the database's blocked-tip curves,
    from 200 to 2500 Pa, F / theta (theta emulated) changes by a factor of 1.2-2.0 (the
    median per group; max / min along a curve) where F / p changes 20-27x with the free
    curve's nonlinearity: the free-curve emulator (~10x as many designs) carries that
    nonlinearity, the force GP only the tip's stiffness over its arm."""
    f = np.asarray(force_mn, float)
    a = np.asarray(angle_deg, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where((a != 0) & np.isfinite(a) & np.isfinite(f), f / a, np.nan)
    return np.arcsinh(k / FORCE_ANGLE_UNIT)


def angle_ratio_from_feature(feature: np.ndarray) -> np.ndarray:
    """F / theta (mN/deg) back from ``force_angle_feature`` (monotone in it)."""
    return FORCE_ANGLE_UNIT * np.sinh(np.asarray(feature, float))


def force_from_angle_ratio(angle: np.ndarray, angle_lo: np.ndarray, angle_hi: np.ndarray,
                           ratio: np.ndarray, ratio_lo: np.ndarray, ratio_hi: np.ndarray
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """F = theta x k (mN) with its band, from the free tip's |angle| (deg) with its band
    and the ratio k = F / theta (mN/deg) with its band: the two errors independent, each
    side's half-width the root sum of squares of the deviations each band alone gives."""
    f = angle * ratio
    # the angle's deviations move F in the direction of k's sign
    da_up, da_dn = angle_hi - angle, angle - angle_lo
    up_a = np.maximum(np.maximum(ratio * da_up, -ratio * da_dn), 0.0)
    dn_a = np.maximum(np.maximum(-ratio * da_up, ratio * da_dn), 0.0)
    up_k, dn_k = angle * (ratio_hi - ratio), angle * (ratio - ratio_lo)
    return f, f - np.hypot(dn_a, dn_k), f + np.hypot(up_a, up_k)


def linear_matrix(nodes: np.ndarray, fine: np.ndarray) -> np.ndarray:
    """Matrix L with L @ f(log nodes) = f linear in log angle between the nodes at log
    ``fine`` (clamped to the node range); every weight is >= 0, so L maps a
    non-negative vector (a band's half-width) to a non-negative one."""
    ln = np.log(nodes)
    lf = np.clip(np.log(fine), ln[0], ln[-1])
    eye = np.eye(len(nodes))
    return np.column_stack([np.interp(lf, ln, eye[i]) for i in range(len(nodes))])


def spline_matrix(nodes: np.ndarray, fine: np.ndarray) -> np.ndarray:
    """Matrix B with B @ f(log nodes) = the natural cubic spline through those values,
    evaluated at log ``fine`` (clamped to the node range): a linear map, so that a
    predicted curve is one matrix product."""
    ln = np.log(nodes)
    lf = np.clip(np.log(fine), ln[0], ln[-1])
    eye = np.eye(len(nodes))
    return np.column_stack([CubicSpline(ln, eye[i], bc_type="natural")(lf)
                            for i in range(len(nodes))])
