"""The emulator of one material group and bending direction (``PairEmulator``).

It holds the group's curve GPs (``curve_gps``) with their band multipliers, where the
group's FE curves end (the FE's stops; the range model, a GP of each database curve's end
angle; the database curves that ended early, with their unit-cube coordinates, end angles,
reasons and last volumes) and the blocked-tip force model (``force_gps``,
``blocked_range``). A design's FE range from these: ``fe_range``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from surrogate.emulator.blocked_range import BlockedRange
from surrogate.emulator.curve_gps import CurveGPs
from surrogate.emulator.early_ended_nodes import (
    AT_CURVE_RADIUS,
    at_curve_weight,
    early_weight,
)
from surrogate.emulator.features import (
    FORCE_PRESSURE_NODES_PA,
    angle_ratio_from_feature,
    between_force_nodes,
    force_at,
    force_from_angle_ratio,
    free_secant_deg_per_pa,
    per_kpa_from_feature,
)
from surrogate.emulator.stretch_hazard import StretchHazard
from surrogate.emulator.vector_gp import MEANS_ONLY, VectorGP

# Unit-cube distance within which a database curve that ended early (volume stop, Newton
# failure) marks the emulator as least reliable (flag near_early_ended_fe_curves): on the
# 36 free-tip curves of two held-out sets of random box designs (2026-12-03, shipped
# 2155-record fit), 6 of the 9 designs within 0.3 of one missed the per-curve target
# (RMSE 1.1-6.2 deg) and 7 had band coverage 0.35-0.76; of the 27 further away, 3 and 4.
NEAR_FAILED_RADIUS = 0.3
FAILED_RADIUS = 0.15      # unit-cube distance within which an early-ended FE curve limits


def nearest_distance(u: np.ndarray, points: np.ndarray | None) -> np.ndarray:
    """Unit-cube distance from each row of ``u`` to the nearest row of ``points`` (inf
    when there are none)."""
    u = np.atleast_2d(u)
    if points is None or not len(points):
        return np.full(len(u), np.inf)
    d2 = np.sum((u[:, None, :] - np.asarray(points)[None, :, :]) ** 2, axis=2)
    return np.sqrt(d2.min(axis=1))


def _end_deg(mean: np.ndarray, var: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The range model's variable (end angle / 90 deg) as the end angle and its sd, deg."""
    return 90.0 * np.asarray(mean), 90.0 * np.sqrt(np.maximum(var, 0.0))


FORCE_FORMS = ("per_kpa", "secant_ratio", "angle_ratio")    # PairEmulator.force_form


def ended_at_volume_stop(reason: str) -> bool:
    """Whether an FE curve's stop reason (``solver.stepping``) is the volume stop."""
    return reason.startswith("reached max_volume_ul")


def ended_at_newton_failure(reason: str) -> bool:
    """Whether an FE curve's stop reason (``solver.stepping``) is a step that did not
    converge, not one of the FE's stops (``reached max_...``)."""
    return not reason.startswith("reached ")


@dataclass(frozen=True)
class PairEmulator:
    """The emulator of one material pair (body, membrane).

    sign                 +1 bends away from the membrane, -1 towards it (reversed pair)
    curves               CurveGPs (``curve_gps``) of (log p_k/theta_k, log V_k/theta_k),
                         k over nodes
    band_scale           (2 N_NODES,) multipliers of the GP sd, one per output node, so
                         that LOO bands cover ``level`` at every angle node
    fe_limit_angle_deg   the FE's last angle on every database curve of the pair
    fe_stop_reason       why the FE curves end there
    force                VectorGP of the force variable at the force nodes, or None
    force_form           what that variable is: "angle_ratio" (``features.force_angle_feature``,
                         F over the free tip's emulated angle at the same pressure; fits
                         since 2026-12-04), "secant_ratio" (``features.force_feature``, F/p
                         over the free tip's emulated secant at 0.1 deg; 2026-12-02) or
                         "per_kpa" (F_j / p_j in mN/kPa, signed; older files)
    near_failed_band_scale  (2 N_NODES,) further multipliers (>= 1) for a design within
                         NEAR_FAILED_RADIUS of an early-ended database curve, calibrated
                         on FE curves of random designs of the box (random_calibration;
                         None: no widening, as in files before format 7)
    force_band_scale     as band_scale, for force (the force GP's sd multiplier, from
                         cross-validation over the database)
    force_band_factor    the force band's half-widths' multiplier from FE curves of random
                         blocked-tip designs of the box (force_calibration; 1: not
                         calibrated, as in files before format 17)
    coordinates          (n, 6) unit-cube coordinates of the database designs
    keys                 their record keys (nearest FE curves)
    """

    pair: str                    # group and sign, e.g. "pdms/ecoflex_00_30+"
    sign: float
    curves: CurveGPs
    band_scale: np.ndarray
    fe_limit_angle_deg: float
    fe_stop_reason: str
    coordinates: np.ndarray
    keys: tuple[str, ...]
    force: VectorGP | None = None
    force_band_scale: float = 1.0
    force_band_factor: float = 1.0
    force_limit_pa: float = float(FORCE_PRESSURE_NODES_PA[-1])
    failed: tuple = ()      # (unit coordinates, end angle deg, reason) of curves ended early
    force_form: str = "per_kpa"
    fe_max_volume_ul: float | None = None   # the FE's volume stop (whole actuator, ul)
    range_model: VectorGP | None = None     # the end angle / 90 deg of the group's curves
    near_failed_band_scale: np.ndarray | None = None
    # where the group's blocked-tip FE curves end (the force's range; None: the group's
    # force range at every design, as in files before format 15)
    blocked_range: BlockedRange | None = None
    # the FE's last injected volume (reduced, ul) of each curve of ``failed``, in its order
    # (None: files before format 15, no volume cap)
    failed_end_volume_ul: np.ndarray | None = None
    # the group's emulated membrane stretch and its FE curves' failures past the hazard
    # stretch (the flag high_membrane_stretch; None: files before format 16)
    stretch_hazard: StretchHazard | None = None

    def __post_init__(self) -> None:
        # the early-ended curves' unit coordinates, stacked once for fe_range's distances
        object.__setattr__(self, "_failed_u", np.array(
            [np.asarray(fu, float) for fu, _, _ in self.failed]) if self.failed else None)
        # and which of them ended at a Newton failure, for end_volume_cap_ul (a loop over
        # them in Python cost 60 us of every query)
        object.__setattr__(self, "_newton_failed", np.array(
            [ended_at_newton_failure(why) for _, _, why in self.failed], bool))

    def failed_distances(self, u: np.ndarray) -> np.ndarray:
        """Unit-cube distance from ``u`` to each database curve of the group that ended
        early (empty when none did)."""
        if self._failed_u is None:
            return np.zeros(0)
        return np.sqrt(np.sum((self._failed_u - u) ** 2, axis=1))

    def nearest_failed(self, u: np.ndarray) -> np.ndarray:
        """Unit-cube distance from each row of ``u`` (m, 6) to the nearest early-ended
        database curve of the group (inf when none ended early)."""
        return nearest_distance(u, self._failed_u)

    def band_scales(self, failed_distance: np.ndarray | float) -> np.ndarray:
        """The sd multipliers of every output node for designs this far (unit cube) from
        the nearest early-ended database curve: ``band_scale``, times
        ``near_failed_band_scale`` within NEAR_FAILED_RADIUS. Rows follow
        ``failed_distance`` (one row for a scalar)."""
        d = np.atleast_1d(np.asarray(failed_distance, float))
        out = np.tile(self.band_scale, (len(d), 1))
        if self.near_failed_band_scale is not None:
            near = d < NEAR_FAILED_RADIUS
            out[near] *= self.near_failed_band_scale
        return out

    def end_volume_cap_ul(self, failed_distances: np.ndarray) -> float | None:
        """The smallest injected volume (reduced, ul) at which an early-ended database curve
        within FAILED_RADIUS (unit cube; ``failed_distances`` from ``failed_distances(u)``)
        ended at a Newton failure, where the FE could go no further; None when none did
        (or the file holds no end volumes). Curves ended at one of the FE's stops (volume,
        angle, pressure: settings, not the physics) do not count."""
        if self.failed_end_volume_ul is None or not len(failed_distances):
            return None
        near = (np.asarray(failed_distances) < FAILED_RADIUS) & self._newton_failed
        return float(np.min(self.failed_end_volume_ul[near])) if near.any() else None

    def ends_short_of_volume_stop_at(self, u: np.ndarray) -> bool:
        """Whether the nearest early-ended database curve of the group lies within
        AT_CURVE_RADIUS of ``u`` and ended before the FE's volume stop (a Newton failure,
        the pressure stop). The balance model is fitted on the curves that reach the
        volume stop and knows none of these: at such database designs it answered 7 of 72
        within 0.2 deg, the curve GPs 39 (thirty-eighth session)."""
        d = self.failed_distances(u)
        if not len(d):
            return False
        i = int(np.argmin(d))
        return bool(d[i] < AT_CURVE_RADIUS) and not ended_at_volume_stop(self.failed[i][2])

    def distance_to_failed(self, u: np.ndarray) -> float:
        """Unit-cube distance from ``u`` to the nearest of them (inf when none)."""
        return float(self.nearest_failed(u)[0])

    def emulated_end_deg(self, u: np.ndarray, with_sd: bool = True
                         ) -> tuple[float, float | None]:
        """Where the FE curve of the design at unit coordinates ``u`` is emulated to end
        (deg) and its sd (``range_model``; needs one). ``with_sd=False``: the mean alone,
        sd None (a query needs the sd only where the end is early or near an early-ended
        curve, ``fe_range``; its variance is most of the range model's cost)."""
        m, var = self.range_model.predict(  # type: ignore[union-attr]
            u, None if with_sd else MEANS_ONLY)
        mean_deg, sd_deg = _end_deg(m[0], var[0])
        return float(mean_deg), (float(sd_deg) if with_sd else None)

    def emulated_ends_deg(self, u: np.ndarray) -> list[tuple[float, float]]:
        """``emulated_end_deg`` at every row of ``u``, in one batch."""
        m, var = self.range_model.predict_many(u)  # type: ignore[union-attr]
        mean_deg, sd_deg = _end_deg(m[:, 0], var[:, 0])
        return list(zip(mean_deg.tolist(), sd_deg.tolist(), strict=True))

    def curve_nodes(self, u: np.ndarray, variance_of: slice | np.ndarray | None = None
                    ) -> tuple[np.ndarray, np.ndarray, tuple[float, float | None] | None,
                               tuple[np.ndarray, np.ndarray] | None]:
        """Node outputs and variances of the design at unit coordinates ``u``
        (``CurveGPs.predict``), the means conditioned on the early-ended database curves
        too as far as the design is emulated to end early or lies at one of them
        (``blend_weights``), that
        emulated end (deg, its sd None: ``fe_range`` asks for it where it is needed; None
        without a range model), and the pressure
        nodes' means and variances without that blend (the force model's angle and its
        band; None where nothing was blended)."""
        end = None if self.range_model is None else self.emulated_end_deg(u, with_sd=False)
        weight = 0.0 if end is None else float(self.blend_weights(u[None, :], [end[0]])[0])
        mean, var, plain = self.curves.predict_with_plain(u, variance_of, weight)
        return mean, var, end, plain

    def curve_nodes_many(self, u: np.ndarray, variance_of: slice | np.ndarray | None = None
                         ) -> tuple[np.ndarray, np.ndarray, list[tuple[float, float] | None],
                                    tuple[np.ndarray, np.ndarray] | None]:
        """``curve_nodes`` at every row of ``u``, in one batch."""
        ends: list[tuple[float, float] | None] = (
            [None] * len(u) if self.range_model is None else self.emulated_ends_deg(u))
        weight = (None if self.range_model is None else self.blend_weights(
            u, [e[0] for e in ends]))  # type: ignore[index]
        mean, var, plain = self.curves.predict_many_with_plain(u, variance_of, weight)
        return mean, var, ends, plain

    def blend_weights(self, u: np.ndarray, end_deg: list[float]) -> np.ndarray:
        """The early-ended curves' blend weight at each row of ``u`` (m, 6), whose FE
        curves are emulated to end at ``end_deg``: ``early_weight`` of that end, or
        ``at_curve_weight`` of the distance to the nearest early-ended database curve of
        this direction that reaches the first node, whichever is larger (at such a
        database design its own curve is reproduced)."""
        weight = early_weight(np.asarray(end_deg, float))
        rows = self.curves.early_ended
        if rows is None:
            return weight
        return np.maximum(weight, at_curve_weight(nearest_distance(u, rows.u)))

    def force_reduced(self, mean: np.ndarray, sd: np.ndarray, node_mean: np.ndarray,
                      p_red: np.ndarray, angle: np.ndarray, angle_lo: np.ndarray,
                      angle_hi: np.ndarray, z: float
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The blocked tip's force (mN, signed, membrane at its preset and W = 3 mm) and its
        band at reduced pressures ``p_red`` (Pa), from the force GP's ``mean`` and ``sd``
        (band scale included) at the force nodes and, for "angle_ratio", the free tip's
        |angle| with its band at the same pressures (deg; NaN past its range). Below the
        first node the first node's value holds (the linear regime)."""
        if self.force_form != "angle_ratio":
            per_kpa = self.force_per_kpa(np.stack((mean, mean - z * sd, mean + z * sd)),
                                         node_mean)
            f, a, b = (force_at(y, p_red) for y in per_kpa)
            return self._calibrated(f, np.fmin(a, b), np.fmax(a, b))
        y, s = between_force_nodes(np.stack((mean, sd)), p_red)
        s = np.maximum(s, 0.0)      # a spline between two small sds may dip below 0
        ratio, lo, hi = (angle_ratio_from_feature(v) for v in (y, y - z * s, y + z * s))
        f, f_lo, f_hi = self._calibrated(*force_from_angle_ratio(angle, angle_lo, angle_hi,
                                                                 ratio, lo, hi))
        if self.sign < 0:       # the ratio is F / theta with theta signed
            return -f, -f_hi, -f_lo
        return f, f_lo, f_hi

    def _calibrated(self, f: np.ndarray, lo: np.ndarray, hi: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The force and its band with each half-width times ``force_band_factor``."""
        k = self.force_band_factor
        if k == 1.0:
            return f, lo, hi
        return f, f - k * (f - lo), f + k * (hi - f)

    def force_end_pa(self, free_end_pa: float, blocked_end_pa: float = float("inf")
                     ) -> float:
        """The highest reduced pressure (Pa) the force is given at: the end of the group's
        blocked-tip FE curves, of the design's own (``blocked_end_pa``, from
        ``blocked_ends_pa``) and, for "angle_ratio" (read off the free curve), of the
        design's free curve, which ends at ``free_end_pa``."""
        end = min(self.force_limit_pa, blocked_end_pa)
        if self.force_form == "angle_ratio":
            return min(end, free_end_pa)
        return end

    def blocked_ends_pa(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The last reduced pressure (Pa) at which each row of ``u`` (m, 6) is given a
        force by where its blocked-tip FE curve is emulated to end, and that end (reduced
        Pa; ``blocked_range.BlockedRange.force_ends_pa``; inf without that model)."""
        if self.blocked_range is None:
            inf = np.full(len(np.atleast_2d(u)), np.inf)
            return inf, inf
        return self.blocked_range.force_ends_pa(u)

    def force_sd_scales(self, blocked_mean_pa: np.ndarray | float) -> np.ndarray | float:
        """The force GP's sd multiplier at each force node (rows: designs whose
        blocked-tip curves are emulated to end at ``blocked_mean_pa``, reduced Pa):
        ``force_band_scale``, times ``BlockedRange.band_scales`` near that end."""
        if self.blocked_range is None or self.force is None:
            return self.force_band_scale
        nodes = FORCE_PRESSURE_NODES_PA[:len(self.force.center)]
        ends = np.asarray(blocked_mean_pa, float)
        return self.force_band_scale * self.blocked_range.band_scales(
            nodes if ends.ndim == 0 else nodes[None, :], ends if ends.ndim == 0
            else ends[:, None])

    def force_per_kpa(self, feature: np.ndarray, node_mean: np.ndarray) -> np.ndarray:
        """F/p (mN/kPa) from the force GP's variable, given the emulated free-curve
        vector(s) ``node_mean`` at the same design(s)."""
        if self.force_form == "per_kpa":
            return np.asarray(feature, float)
        return per_kpa_from_feature(feature, free_secant_deg_per_pa(node_mean, self.sign))

