"""A design's emulated curve: p(theta) with its band, V(theta), and its FE range.

``CurveBand`` is what a query reads a design's answers off (by pressure, by volume, the
inverse, the force); ``design_curve_band`` computes it from the design's pair emulator.
Reduced: the membrane at stiffness scale 1 and W = 3 mm (``solver.design_space``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from solver.design_space import BoxPoint
from surrogate.emulator.fe_range import fe_range
from surrogate.emulator.features import FINE_ANGLES_DEG, N_NODES
from surrogate.emulator.node_curves import _monotone, _with_origin, node_curves
from surrogate.emulator.pair_emulator import PairEmulator
from surrogate.emulator.volume_curve import emulated_volume_ul, volume_shape

if TYPE_CHECKING:
    from surrogate.emulator.emulator import Emulator


@dataclass(frozen=True)
class CurveBand:
    """p(theta) on FINE_ANGLES_DEG for one design, reduced pressure (membrane at s = 1):
    mean and the band's lower/upper pressure curves, and V(theta) (ul, reduced)."""

    pressure_pa: np.ndarray
    pressure_lower_pa: np.ndarray
    pressure_upper_pa: np.ndarray
    volume_ul: np.ndarray
    limit_angle_deg: float
    stop_reason: str
    volume_log_mean: np.ndarray     # emulated log(V_k / theta_k) at the nodes
    volume_log_sd: np.ndarray       # its sd, times the band scale
    pressure_raw_pa: np.ndarray     # the mean p(theta) before it is made monotone
    node_mean: np.ndarray           # the emulated node vector (force normalisation)
    coordinates: np.ndarray         # the design's unit-cube coordinates (force model)
    failed_distance: float = float("inf")  # to the nearest early-ended database curve
    # p(theta), lower and upper, of the complete-curve GPs alone, where the answer's
    # blends in the early-ended curves (early_ended_nodes): the force model's angle
    # (None: the answer's own)
    force_reference: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    # the range ends at the FE's pressure stop (pressure_stop_angle), not where the
    # curves here end: the points past it are flagged past_fe_pressure_stop too
    pressure_stopped: bool = False
    # the last reduced pressure (Pa) at which the force is given by where this design's
    # blocked-tip FE curve is emulated to end (PairEmulator.blocked_ends_pa)
    blocked_end_pa: float = float("inf")
    blocked_mean_pa: float = float("inf")   # that curve's emulated end (reduced Pa)
    # the angle (deg, unsigned) from which the emulated membrane stretch passes the
    # hazard stretch (StretchHazard.onset_deg; inf: it does not, or no such model)
    stretch_onset_deg: float = float("inf")

    @property
    def limit_pressure_pa(self) -> float:
        return float(np.interp(self.limit_angle_deg, FINE_ANGLES_DEG, self.pressure_pa))


def design_curve_band(emulator: Emulator, pe: PairEmulator, point: BoxPoint,
                      u: np.ndarray, z: float, volume_band: bool) -> CurveBand:
    """``Emulator.curve_band`` computed, by ``pe`` (the design's pair emulator) at
    unit coordinates ``u``: the band at +-``z`` sd, the band of V(theta) only with
    ``volume_band``."""
    if pe.curves.per_output:
        nodes = emulator.variance_nodes
        which = (np.concatenate((nodes, np.arange(N_NODES, 2 * N_NODES)))
                 if volume_band else nodes)
        mean, var, end, plain = pe.curve_nodes(u, variance_of=which)
        var = emulator.spread_variance(var)
    else:
        mean, var, end, plain = pe.curve_nodes(u)
    failed = pe.failed_distances(u)
    nearest = float(failed.min()) if failed.size else float("inf")
    scales = pe.band_scales(nearest)[0]
    sd = np.sqrt(var[:N_NODES]) * scales[:N_NODES]
    p_raw, lo, hi = node_curves(mean[:N_NODES], sd, z)
    p, lo, hi = _monotone(p_raw), _monotone(lo), _monotone(hi)
    v = emulated_volume_ul(mean[N_NODES:])
    limit, reason = fe_range(pe, u, v, point.length_scale, emulated_end=end,
                             failed_distances=failed)
    v_sd = np.sqrt(var[N_NODES:]) * scales[N_NODES:]
    reference = None
    if pe.force is not None and plain is not None:
        # the force model's F / theta was fitted to the complete-curve GPs' angle
        # (force_fit.force_angle_rows): the same angle, and its band, multiply it here
        p_mean, p_var = plain
        if pe.curves.per_output:
            p_var = emulator.spread_variance(np.concatenate((p_var, var[N_NODES:])))
        p_sd = np.sqrt(p_var[:N_NODES]) * scales[:N_NODES]
        reference = tuple(_monotone(c) for c in node_curves(p_mean, p_sd, z))
    blocked = (pe.blocked_ends_pa(u) if pe.force is not None
               else (np.full(1, np.inf), np.full(1, np.inf)))
    onset = (float("inf") if pe.stretch_hazard is None
             else pe.stretch_hazard.onset_deg(u))
    return CurveBand(p, lo, hi, v, limit, reason, mean[N_NODES:], v_sd, p_raw, mean, u,
                     nearest, reference, blocked_end_pa=float(blocked[0][0]),
                     blocked_mean_pa=float(blocked[1][0]), stretch_onset_deg=onset)


def volume_curves(cb: CurveBand, z: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """V(theta) on ANGLES0 (reduced, ul): mean and the band's low and high curves."""
    return volume_band_ul(cb.volume_log_mean, cb.volume_log_sd, z)


def volume_band_ul(log_mean: np.ndarray, log_sd: np.ndarray, z: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """V(theta) on ANGLES0 (reduced, ul) of one design from its volume nodes' emulated
    log(V / theta) and sd (band scale included): mean and the band's low and high curves
    at -+ ``z`` sd, each made to rise as the FE's volumes do (``volume_shape``)."""
    return tuple(_with_origin(volume_shape(c))  # type: ignore[return-value]
                 for c in node_curves(log_mean, log_sd, z))
