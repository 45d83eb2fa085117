"""The design-space emulator: FE curves interpolated across the box, with bands.

For each material pair, every free-tip FE curve of the database is a vector of node
values (``features``: secant stiffness log(p/theta) and secant volume log(V/theta) at
fixed angles); one Gaussian process per node (``vector_gp.fit_output_gps``) interpolates that
vector over the box's unit-cube coordinates (``solver.design_space``). A query

1. maps the design to the reduced box (lengths / (W / 3 mm), body stiffness relative
   to the membrane's; pressure scale = the membrane's stiffness scale),
2. predicts the node values and their variance, draws p(theta) through them (a linear
   spline map), and reads angle(p) off the monotone curve,
3. gives the band as the horizontal band of the p(theta) curves at +-z sd (scaled by
   ``band_scale``, one per node, calibrated on leave-one-out FE curves), so it is monotone too,
4. refuses every pressure past the FE's range: the database curves end at the FE's
   stop (``fe_limit_angle_deg``, 90 deg unless a curve failed earlier) and past it the
   answer is NaN with the flag ``past_fe_range``.

Force: blocked-tip FE curves, read at fixed pressures as the ratio of the blocked tip's
force to the free tip's emulated angle at the same pressure (``features.force_angle_feature``),
emulated the same way; the answer is that ratio times the free tip's emulated angle, its
band the two bands combined. F scales with the membrane's stiffness scale s (p / s fixed)
and with the square of the length scale. Volume scales with the cube of the length scale.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from solver.design import Design
from solver.design_space import PAIRS, BoxPoint, locate
from solver.errors import InputError
from solver.settings import SolverSettings
from surrogate.band_level import z_value
from surrogate.emulator.balance import VOLUME_NODES_UL, BalanceModel, first_reach
from surrogate.emulator.blocked_range import BlockedRange
from surrogate.emulator.curve_gps import CurveGPs
from surrogate.emulator.design_memo import DesignMemo
from surrogate.emulator.early_ended_nodes import (
    AT_CURVE_RADIUS,
    at_curve_weight,
    early_weight,
)
from surrogate.emulator.features import (
    ANGLE_BAND_FLOOR_DEG,
    ANGLE_NODES_DEG,
    FINE_ANGLES_DEG,
    FORCE_PRESSURE_NODES_PA,
    N_NODES,
    angle_ratio_from_feature,
    force_at,
    force_from_angle_ratio,
    free_secant_deg_per_pa,
    linear_matrix,
    per_kpa_from_feature,
    spline_matrix,
)
from surrogate.emulator.variance_nodes import FORMAT_7_NODES, spline, spread_variance
from surrogate.emulator.vector_gp import MEANS_ONLY, VectorGP
from surrogate.predictor import (
    FE_PRESSURE_STOP_PA,
    InversePrediction,
    Prediction,
    band_within_fe,
    number_array,
    one_signed,
    pressure_stop_reason,
)
from surrogate.volume_control import by_volume

# Unit-cube distance within which a database curve that ended early (volume stop, Newton
# failure) marks the emulator as least reliable (flag near_early_ended_fe_curves): on the
# 36 free-tip curves of two held-out sets of random box designs (2026-12-03, shipped
# 2155-record fit), 6 of the 9 designs within 0.3 of one missed the per-curve target
# (RMSE 1.1-6.2 deg) and 7 had band coverage 0.35-0.76; of the 27 further away, 3 and 4.
NEAR_FAILED_RADIUS = 0.3
# A design this many times the box's size (W / 3 mm) or larger that reaches the FE's volume
# stop is told so, not that its balloon grows more than it bends: at W = 20 mm the curve
# ended at 0.2 deg for its k^3 = 296x volume, explained as a balloon that does not bend
# (the explorer audit of the thirty-seventh session).
VOLUME_STOP_SCALE = 1.5
FAILED_RADIUS = 0.15      # unit-cube distance within which an early-ended FE curve limits
# The emulated end of a design's FE curve (PairEmulator.range_model, a GP of where every
# database curve of the group ends: 90 deg, or earlier at the volume stop or a Newton
# failure) caps the range at its mean less RANGE_Z sd. The curves interpolated are the
# complete ones only; where most neighbours ended early (near the Ecoflex/Ecoflex balance,
# where the membrane balloons and the actuator hardly bends) the emulated V(theta) learnt
# nothing of them and did not reach the volume stop: a held-out design there whose FE
# stopped at 58 deg (500 ul) was answered to 88 deg, 30 deg off.
RANGE_Z = 1.0
# An emulated end at or above RANGE_COMPLETE_DEG is read as the FE's 90-deg angle stop,
# not as an early end: the range model's mean for a design among complete curves sits at
# 90 +/- its sd (median sd 6.3 deg), and mean - RANGE_Z sd cut 399 of the 415 complete FE
# curves of random designs at a median 83.8 deg, with a reason ("nearby curves end early")
# that was false. Of the 64 early-ended ones (range model means 19-81 deg, 5-95 %), none
# changes its cut at 85 (benchmarks/RESULTS.md, thirty-sixth session).
RANGE_COMPLETE_DEG = 85.0
SIGN_MARGIN = 0.5         # |sign model| below this: too near the stiffness balance
# The balance model (surrogate.emulator.balance) also answers where it says the FE curve
# ends at the volume stop: its angle at the last volume node plus BALANCE_TOP_Z of its sd
# below BALANCE_TOP_DEG. On the 121 Ecoflex/Ecoflex FE curves of random designs (band
# calibration and held-out sets) with a direction, the 33 so chosen were within the
# per-curve target on 23 by volume and 23 by pressure, against 8 and 21 answered by the
# per-direction curve GPs (benchmarks/RESULTS.md, twenty-fifth session; 70-90 deg chose
# the same curves, the largest 77.9).
BALANCE_TOP_DEG = 80.0
BALANCE_TOP_Z = 2.0
# ... unless the direction's range model emulates the FE curve to reach this (a database
# curve that reached 90 deg at 115 ul was answered 35 deg off by the balance model, which
# only knows curves that end at the volume stop; of the 460 designs of the database and
# the random-design sets it chose, that was the one emulated to end at 89 deg or later)
BALANCE_COMPLETE_DEG = 89.0
# The balance model answers up to this share of the FE's volume stop (its curves end past
# it, at the first step beyond) or its last node, whichever is smaller.
BALANCE_VOLUME_MARGIN = 0.96
# A design whose group and side (near or far from early-ended curves) had its band cover
# less than this share of the points of FE curves of random designs, after the band's
# second calibration, on at least UNDERCOVER_MIN_POINTS of them, is flagged
# ``band_undercovers_random_designs`` (the honest range is 0.90-0.98).
UNDERCOVER_LEVEL = 0.90
UNDERCOVER_MIN_POINTS = 40
# A fall of the emulated p(theta) below its running maximum counts as a pressure maximum
# from this relative size on: smaller wiggles (the shipped fit's largest is 2.5e-4) are far
# inside the band (a few per cent) and say nothing about the physics.
EMULATED_PRESSURE_DROP = 1e-3
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


def _direction(m: np.ndarray) -> np.ndarray:
    """+1 / -1 from a sign model's mean; 0 within SIGN_MARGIN of the balance, where the
    FE data do not tell which way the design bends."""
    return np.where(np.abs(m) < SIGN_MARGIN, 0.0, np.sign(m))


FORCE_BAND_LIMIT = 2.0     # widest force band answered, relative to the force
# A force band narrower than this (mN, full width) is answered whatever its relative width:
# the blocked tip's first steps (0.01 uN at 25 Pa on the standard design, its band 0.2 uN
# wide: the initial reaction's sign is uncertain) are far below what a lab's force sensor
# resolves, and withholding them only raised the flag on every design.
FORCE_BAND_FLOOR_MN = 2e-3


def force_backed(force: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Where a force answer is given: its band (mN) within FORCE_BAND_LIMIT x the force,
    or narrower than FORCE_BAND_FLOOR_MN. A NaN force or band (no force answer) is not
    backed."""
    with np.errstate(invalid="ignore"):
        width = np.asarray(upper, float) - np.asarray(lower, float)
        relative = width <= FORCE_BAND_LIMIT * np.abs(np.asarray(force, float)) + 1e-9
        return relative | (width <= FORCE_BAND_FLOOR_MN)


FORCE_FORMS = ("per_kpa", "secant_ratio", "angle_ratio")    # PairEmulator.force_form


def ended_at_volume_stop(reason: str) -> bool:
    """Whether an FE curve's stop reason (``solver.stepping``) is the volume stop."""
    return reason.startswith("reached max_volume_ul")


def ended_at_newton_failure(reason: str) -> bool:
    """Whether an FE curve's stop reason (``solver.stepping``) is a step that did not
    converge, not one of the FE's stops (``reached max_...``)."""
    return not reason.startswith("reached ")


def end_volume_reason(volume_ul: float) -> str:
    """Why a design's range ends at ``volume_ul`` injected (whole actuator, ul): the
    volume at which early-ended database curves within FAILED_RADIUS ended
    (``PairEmulator.end_volume_cap_ul``, scaled to the design's size)."""
    return (f"the FE curves of nearby database designs ended at about {volume_ul:.0f} ul "
            "injected (at this design's size; a Newton failure, where the FE could go no "
            "further)")


def balance_message(designs: int) -> str:
    """What an answer near the stiffness balance is read from (its first message)."""
    return ("this design sits near the balance of the two layers' stiffness, where both "
            "balloon alike and the FE curve ends at the volume stop short of 90 deg (either "
            "way round): answered by the signed angle at fixed injected volumes, "
            f"interpolated across the balance from {designs} FE curves that end there "
            "(docs/surrogate.md); ")


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
    force_band_scale     as band_scale, for force
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

    def emulated_end_deg(self, u: np.ndarray) -> tuple[float, float]:
        """Where the FE curve of the design at unit coordinates ``u`` is emulated to end
        (deg) and its sd (``range_model``; needs one)."""
        m, var = self.range_model.predict(u)  # type: ignore[union-attr]
        mean_deg, sd_deg = _end_deg(m[0], var[0])
        return float(mean_deg), float(sd_deg)

    def emulated_ends_deg(self, u: np.ndarray) -> list[tuple[float, float]]:
        """``emulated_end_deg`` at every row of ``u``, in one batch."""
        m, var = self.range_model.predict_many(u)  # type: ignore[union-attr]
        mean_deg, sd_deg = _end_deg(m[:, 0], var[:, 0])
        return list(zip(mean_deg.tolist(), sd_deg.tolist(), strict=True))

    def curve_nodes(self, u: np.ndarray, variance_of: slice | np.ndarray | None = None
                    ) -> tuple[np.ndarray, np.ndarray, tuple[float, float] | None,
                               tuple[np.ndarray, np.ndarray] | None]:
        """Node outputs and variances of the design at unit coordinates ``u``
        (``CurveGPs.predict``), the means conditioned on the early-ended database curves
        too as far as the design is emulated to end early or lies at one of them
        (``blend_weights``), that
        emulated end (deg, with its sd; None without a range model), and the pressure
        nodes' means and variances without that blend (the force model's angle and its
        band; None where nothing was blended)."""
        end = None if self.range_model is None else self.emulated_end_deg(u)
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

    def fe_range(self, u: np.ndarray, volume_red_ul: np.ndarray, length_scale: float,
                 emulated_end: tuple[float, float] | None = None,
                 failed_distances: np.ndarray | None = None) -> tuple[float, str]:
        """The FE's range for the design at unit coordinates ``u`` (deg) and why it ends
        there: the FE's angle stop; the angle at which the emulated injected volume
        ``volume_red_ul`` (reduced, on FINE_ANGLES_DEG) reaches the FE's volume stop; the
        emulated end of the design's FE curve less RANGE_Z sd (``range_model``; pass
        ``emulated_end_deg(u)`` as ``emulated_end`` when it is already known) where that
        end is below RANGE_COMPLETE_DEG or an early-ended database curve lies within
        NEAR_FAILED_RADIUS; the end of an early-ended database curve within FAILED_RADIUS
        (``failed_distances(u)`` when already known); the angle at which the emulated
        volume reaches the last FE volume of such a curve that ended at a Newton failure
        (``end_volume_cap_ul``: near such an end the emulated V(theta) is least sure;
        database design dad39d92, whose FE failed at 71.3 deg and 142.6 ul, was answered by
        volume to 199.5 ul)."""
        limit, reason = self.fe_limit_angle_deg, self.fe_stop_reason
        if failed_distances is None:
            failed_distances = self.failed_distances(u)
        if self.range_model is not None:
            mean_deg, sd_deg = (self.emulated_end_deg(u) if emulated_end is None
                                else emulated_end)
            end = max(mean_deg - RANGE_Z * sd_deg, 0.0)
            ends_early = mean_deg < RANGE_COMPLETE_DEG
            near = bool((failed_distances < NEAR_FAILED_RADIUS).any())
            if (ends_early or near) and end < limit - 1.0:
                limit = end
                why = ("this design's FE curve is emulated to end early too, at "
                       f"{mean_deg:.0f} +/- {sd_deg:.0f} deg" if ends_early else
                       f"one lies within {NEAR_FAILED_RADIUS:g} of this design (unit box), "
                       f"and where this design's ends is uncertain ({mean_deg:.0f} +/- "
                       f"{sd_deg:.0f} deg)")
                reason = ("FE curves of database designs in this neighbourhood end early (the "
                          "volume stop, where the balloon grows more than the actuator "
                          f"bends, or a Newton failure): {why}; its range is taken to end "
                          f"{RANGE_Z:g} sd short of the emulated end")
        if self.fe_max_volume_ul is not None:
            at_stop = angle_at_volume_deg(volume_red_ul, self.fe_max_volume_ul / length_scale**3)
            if at_stop is not None and at_stop < limit:
                limit = at_stop
                reason = (f"the default FE stops at {self.fe_max_volume_ul:g} ul injected "
                          "(SolverSettings.max_volume_ul), which this design's emulated "
                          "volume reaches there: " + (
                              "the balloon grows more than the actuator bends"
                              if length_scale <= VOLUME_STOP_SCALE else
                              f"a copy {length_scale:.3g}x the box's size in every length "
                              f"holds {length_scale**3:.3g}x its volume, so it reaches the "
                              "stop at a smaller angle (POST /v1/solve with a larger "
                              "max_volume_ul gives the rest)"))
        cap_ul = self.end_volume_cap_ul(failed_distances)
        at_cap = None if cap_ul is None else angle_at_volume_deg(volume_red_ul, cap_ul)
        if at_cap is not None and at_cap < limit:
            limit = at_cap
            reason = (end_volume_reason(cap_ul * length_scale**3) + ", which this design's "
                      "emulated volume reaches there")
        if self.failed:
            near = failed_distances < FAILED_RADIUS
            for i in np.flatnonzero(near):
                _, angle, why = self.failed[i]
                if angle < limit:
                    limit = float(angle)
                    reason = f"the FE curve of a nearby database design ended there: {why}"
        return limit, reason

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
            return f, np.fmin(a, b), np.fmax(a, b)
        q = FORCE_PRESSURE_NODES_PA[:len(mean)]
        y, s = np.interp(p_red, q, mean), np.interp(p_red, q, sd)
        ratio, lo, hi = (angle_ratio_from_feature(v) for v in (y, y - z * s, y + z * s))
        f, f_lo, f_hi = force_from_angle_ratio(angle, angle_lo, angle_hi, ratio, lo, hi)
        if self.sign < 0:       # the ratio is F / theta with theta signed
            return -f, -f_hi, -f_lo
        return f, f_lo, f_hi

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

    @property
    def limit_pressure_pa(self) -> float:
        return float(np.interp(self.limit_angle_deg, FINE_ANGLES_DEG, self.pressure_pa))




def pressure_stop_angle(limit_deg: float, angles_deg: np.ndarray,
                        pressure_red_pa: np.ndarray, pressure_scale: float) -> float | None:
    """The angle (deg) where a design's emulated mean p(theta) (``pressure_red_pa`` at
    ``angles_deg``, reduced: the membrane at s = 1, non-decreasing) reaches the FE's
    pressure stop, FE_PRESSURE_STOP_PA / ``pressure_scale`` reduced, when that comes
    before the range's end ``limit_deg``; None when it does not. The memoised curve is
    shared by every pressure scale of a reduced design, so the stop is applied per
    question: layers 50x their presets were answered to 105843 Pa in Python while the
    default FE stops at 20 kPa."""
    stop_red = FE_PRESSURE_STOP_PA / pressure_scale
    if float(np.interp(limit_deg, angles_deg, pressure_red_pa)) <= stop_red:
        return None
    return float(np.interp(stop_red, pressure_red_pa, angles_deg))


def floored_band(angle: np.ndarray, lower: np.ndarray, upper: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The band (lower, upper) widened to at least ANGLE_BAND_FLOOR_DEG either side of
    ``angle`` (deg; NaN stays NaN)."""
    return (np.fmin(lower, angle - ANGLE_BAND_FLOOR_DEG),
            np.fmax(upper, angle + ANGLE_BAND_FLOOR_DEG))


def _monotone(p: np.ndarray) -> np.ndarray:
    return np.maximum.accumulate(p)


# The injected volume's shape: on every complete free-tip FE curve of the balanced
# database (1526 curves, 2026-12-04) the local exponent d log V / d log theta stays above
# 0.41 from 20 deg on (1 % quantile of each curve's minimum 0.46-0.48, median 0.60).
VOLUME_EXPONENT_FLOOR = 0.4
VOLUME_FLOOR_FROM_DEG = 20.0
_VOLUME_FLOOR_STEP = np.concatenate(([0.0], np.where(
    FINE_ANGLES_DEG[1:] > VOLUME_FLOOR_FROM_DEG,
    VOLUME_EXPONENT_FLOOR * np.diff(np.log(FINE_ANGLES_DEG)), 0.0)))
_VOLUME_FLOOR = np.cumsum(_VOLUME_FLOOR_STEP)


def volume_shape(v: np.ndarray) -> np.ndarray:
    """An emulated V(theta) on FINE_ANGLES_DEG (ul, > 0; rows of a 2-D ``v`` are designs)
    made to rise as the FE's do: never falling, and from VOLUME_FLOOR_FROM_DEG on at least
    as theta^VOLUME_EXPONENT_FLOOR from any earlier point (log V - floor is made
    non-decreasing, floor the cumulative minimum rise). Where the GP's log(V/theta) falls
    too steeply at high angles (it did near early-ended Ecoflex/Ecoflex curves, volume
    flat from 66 to 89 deg where the FE's rose 45 -> 67 ul), the running maximum alone
    left a plateau, and the angle read at a volume on it jumped by 20 deg or more."""
    lv = np.log(v) - _VOLUME_FLOOR
    return np.exp(np.maximum.accumulate(lv, axis=-1) + _VOLUME_FLOOR)


def angle_at_volume_deg(volume_red_ul: np.ndarray, v_red: float) -> float | None:
    """The angle (deg) at which an emulated V(theta) (``volume_red_ul``: reduced ul on
    FINE_ANGLES_DEG, non-decreasing, ``volume_shape``) reaches the reduced volume
    ``v_red`` (ul), linear between the fine angles as a query by volume reads it (so that
    the range's end by volume is ``v_red`` itself); None where it does not."""
    v = np.asarray(volume_red_ul, float)
    if v[-1] < v_red:
        return None
    return float(np.interp(v_red, _with_origin(v), ANGLES0))


def emulated_volume_ul(log_v_nodes: np.ndarray) -> np.ndarray:
    """The emulated V(theta) on FINE_ANGLES_DEG (reduced ul; rows of a 2-D input are
    designs) from the volume nodes' log(V / theta): the natural spline through them, made
    to rise as the FE volumes do (``volume_shape``)."""
    return volume_shape(FINE_ANGLES_DEG * np.exp(log_v_nodes @ _B_ANGLE.T))


def _with_origin(x: np.ndarray) -> np.ndarray:
    return np.concatenate(([0.0], x))


ANGLES0 = _with_origin(FINE_ANGLES_DEG)


@dataclass(frozen=True)
class Emulator:
    """The default predictor: implements ``surrogate.predictor.Predictor``."""

    name: str
    pairs: dict[str, PairEmulator]        # by group and sign ("pdms/ecoflex_00_30+")
    provenance: dict = field(default_factory=dict)
    report: dict = field(default_factory=dict)
    sign_models: dict[str, VectorGP] = field(default_factory=dict)
    # the pressure nodes a query computes the exact variance at, chosen by the fit
    # (surrogate.emulator.variance_nodes; files before format 8: FORMAT_7_NODES)
    variance_nodes: np.ndarray = field(default_factory=FORMAT_7_NODES.copy)
    # where a group's sign model cannot tell the direction: the signed angle by injected
    # volume (surrogate.emulator.balance; files before format 12: none, refused)
    balance_models: dict[str, BalanceModel] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_variance_spline", spline(self.variance_nodes))
        # the last designs' curves and balance decisions (design_memo.py); a new object
        # (dataclasses.replace: refitted bands) starts empty
        object.__setattr__(self, "_memo", DesignMemo())

    def warm_up(self) -> None:
        """Make what the first query of every group needs and keeps: each kernel's L^-1 and
        K that a variance reads (``VectorGP``, made on a kernel's first variance, not at
        loading: 0.05-0.15 s a group by pressure, 0.3-0.6 s by volume, the 32 volume
        kernels). One query's GP work at each pair's first database design on both axes,
        its force model and its group's balance model; nothing is remembered as an answer
        (the design memo is not touched). The service runs it after start-up, in the
        background; the CLI answers one design and does not."""
        which = np.concatenate((self.variance_nodes, np.arange(N_NODES, 2 * N_NODES)))
        for pe in self.pairs.values():
            u = pe.curves.gp.gps[0].x[0]
            pe.curve_nodes(u, variance_of=which if pe.curves.per_output else None)
            if pe.force is not None:
                pe.force.predict(pe.force.gps[0].x[0])
        for model in self.balance_models.values():
            u = model.gp.gps[0].x[0]
            model.nodes(u)
            model.top_deg(u, 1.0)

    def spread_variance(self, var: np.ndarray) -> np.ndarray:
        """``var`` with every pressure node's variance read off those at variance_nodes."""
        return spread_variance(var, self.variance_nodes,
                               self._variance_spline)  # type: ignore[attr-defined]

    # -- the curve of one design --------------------------------------------------------
    def _sign(self, point: BoxPoint, u: np.ndarray | None = None) -> float:
        """The bending direction at ``point``: the group's sign model where the group bends
        both ways (InputError near the balance), else the one sign the data has."""
        model = self.sign_models.get(point.group)
        if model is None:
            return self._one_sign(point.group)
        m = model.predict(point.coordinates() if u is None else u,
                          variance_of=MEANS_ONLY)[0][:1]
        sign = float(_direction(m)[0])
        if sign == 0.0:
            raise InputError("design", "this design sits near the balance of the two layers' "
                             "stiffness, where the membrane and the body balloon alike: it "
                             "bends little and the FE data do not tell which way",
                             "a stiffness contrast further from 1 (a stiffer body or a softer "
                             "membrane), or an FE solve of this design (POST /v1/solve)")
        return sign

    def balance_model_for(self, point: BoxPoint) -> BalanceModel | None:
        """The group's balance model where it answers for ``point``: the sign model cannot
        tell the direction (within SIGN_MARGIN of the balance), or the design's FE curve
        ends at the volume stop, the balance model's angle at its last node and
        BALANCE_TOP_Z of its sd short of BALANCE_TOP_DEG and the direction's range model
        short of BALANCE_COMPLETE_DEG (a curve that reaches 90 deg first is the
        per-direction curve GPs'). None elsewhere, and for groups without one."""
        model = self.balance_models.get(point.group)
        if model is None:
            return None
        u = point.coordinates()
        answers = self._memo.get_or_make(  # type: ignore[attr-defined]
            ("balance", point.group, u.tobytes()),
            lambda: self._balance_answers(point.group, model, u))
        return model if answers else None

    def _balance_answers(self, group: str, model: BalanceModel, u: np.ndarray) -> bool:
        """Whether ``model`` answers for the design at unit coordinates ``u`` of ``group``
        (``balance_model_for``)."""
        m = self.sign_models[group].predict(u, variance_of=MEANS_ONLY)[0][:1]
        sign = _direction(m)[0]
        if sign == 0.0:
            return True
        top = model.top_deg(u, BALANCE_TOP_Z)
        if top >= BALANCE_TOP_DEG:
            return False
        # the balance model knows no curve that reaches 90 deg before the volume stop: where
        # the direction's range model says the FE curve is complete, it is the curve GPs'
        pe = self.pairs.get(group + ("+" if sign > 0 else "-"))
        if pe is not None and pe.ends_short_of_volume_stop_at(u):
            return False
        if pe is not None and pe.range_model is not None:
            if pe.emulated_end_deg(u)[0] >= BALANCE_COMPLETE_DEG:
                return False
        return True

    def _one_sign(self, group: str) -> float:
        """The sign of a group that bends one way only (no sign model)."""
        return 1.0 if group + "+" in self.pairs else -1.0

    def _signed_groups(self, points: list[BoxPoint], coords: np.ndarray
                       ) -> dict[str, list[int]]:
        """Indices of ``points`` (unit coordinates ``coords``) by group and bending
        direction, as ``_sign`` gives it one at a time (the sign models' means in one
        batch); points near a balance are left out."""
        out: dict[str, list[int]] = {}
        by_group: dict[str, list[int]] = {}
        for i, pt in enumerate(points):
            by_group.setdefault(pt.group, []).append(i)
        for group, idx in by_group.items():
            model = self.sign_models.get(group)
            signs = (np.full(len(idx), self._one_sign(group)) if model is None else
                     _direction(model.predict_many(coords[idx], variance_of=MEANS_ONLY)[0][:, 0]))
            for i, sign in zip(idx, signs, strict=True):
                if sign != 0.0:
                    out.setdefault(group + ("+" if sign > 0 else "-"), []).append(i)
        return out

    def _pair(self, point: BoxPoint, u: np.ndarray | None = None) -> PairEmulator:
        return self.pairs[self._pair_key(point, u)]

    def _pair_key(self, point: BoxPoint, u: np.ndarray | None = None) -> str:
        """The key of the pair emulator that answers for ``point`` (group and direction)."""
        sign = self._sign(point, u)
        key = point.group + ("+" if sign > 0 else "-")
        if key not in self.pairs:
            here = "away from" if sign > 0 else "towards"
            other = "towards" if sign > 0 else "away from"
            raise InputError("body_material", f"{point.pair[0]} on {point.pair[1]} bends "
                             f"{here} the membrane at this stiffness contrast, a direction "
                             f"of this pair that the emulator '{self.name}' has too few FE "
                             "curves of to emulate",
                             f"a stiffness contrast at which this pair bends {other} the "
                             "membrane, as its database curves do, or an FE solve of this "
                             "design (POST /v1/solve)")
        return key

    def curve_band(self, point: BoxPoint, z: float, volume_band: bool = True
                   ) -> tuple[PairEmulator, CurveBand]:
        """The design's p(theta) with its band and V(theta); the band of V(theta)
        (``volume_log_sd``) only with ``volume_band`` (NaN otherwise: half the cost of a
        query with one GP per node). Kept for the design's next question (design_memo.py;
        its arrays read-only)."""
        u = point.coordinates()     # once: the sign, curves, range and force models
        key = ("curve", point.group, u.tobytes(), float(point.length_scale), float(z))
        memo = self._memo  # type: ignore[attr-defined]
        # the curve with its volume band answers a question that does not need that band
        # too (the same curve: the band of V(theta) is the only difference)
        kept = memo.get(key + (True,))
        if kept is None:
            kept = memo.get_or_make(key + (bool(volume_band),),
                                    lambda: self._curve_band(point, u, z, volume_band))
        pair_key, band = kept
        at_stop = pressure_stop_angle(band.limit_angle_deg, FINE_ANGLES_DEG, band.pressure_pa,
                                      point.pressure_scale)
        if at_stop is not None:
            band = replace(band, limit_angle_deg=at_stop, pressure_stopped=True,
                           stop_reason=pressure_stop_reason(
                               band.limit_pressure_pa * point.pressure_scale))
        return self.pairs[pair_key], band

    def _curve_band(self, point: BoxPoint, u: np.ndarray, z: float, volume_band: bool
                    ) -> tuple[str, CurveBand]:
        """``curve_band`` computed: the pair emulator's key and the design's curve."""
        pair_key = self._pair_key(point, u)
        pe = self.pairs[pair_key]
        if pe.curves.per_output:
            nodes = self.variance_nodes
            which = (np.concatenate((nodes, np.arange(N_NODES, 2 * N_NODES)))
                     if volume_band else nodes)
            mean, var, end, plain = pe.curve_nodes(u, variance_of=which)
            var = self.spread_variance(var)
        else:
            mean, var, end, plain = pe.curve_nodes(u)
        failed = pe.failed_distances(u)
        nearest = float(failed.min()) if failed.size else float("inf")
        scales = pe.band_scales(nearest)[0]
        sd = np.sqrt(var[:N_NODES]) * scales[:N_NODES]
        p_raw, lo, hi = node_curves(mean[:N_NODES], sd, z)
        p, lo, hi = _monotone(p_raw), _monotone(lo), _monotone(hi)
        v = emulated_volume_ul(mean[N_NODES:])
        limit, reason = pe.fe_range(u, v, point.length_scale, emulated_end=end,
                                    failed_distances=failed)
        v_sd = np.sqrt(var[N_NODES:]) * scales[N_NODES:]
        reference = None
        if pe.force is not None and plain is not None:
            # the force model's F / theta was fitted to the complete-curve GPs' angle
            # (build.force_angle_rows): the same angle, and its band, multiply it here
            p_mean, p_var = plain
            if pe.curves.per_output:
                p_var = self.spread_variance(np.concatenate((p_var, var[N_NODES:])))
            p_sd = np.sqrt(p_var[:N_NODES]) * scales[:N_NODES]
            reference = tuple(_monotone(c) for c in node_curves(p_mean, p_sd, z))
        blocked = (pe.blocked_ends_pa(u) if pe.force is not None
                   else (np.full(1, np.inf), np.full(1, np.inf)))
        return pair_key, CurveBand(p, lo, hi, v, limit, reason, mean[N_NODES:], v_sd, p_raw,
                                   mean, u, nearest, reference,
                                   blocked_end_pa=float(blocked[0][0]),
                                   blocked_mean_pa=float(blocked[1][0]))

    # -- Predictor -----------------------------------------------------------------------
    def predict(self, design: Design, pressures_pa: object, level: float = 0.95
                ) -> Prediction:
        """Angle (deg) at each chamber pressure (Pa), band at ``level``, force (mN) of the
        blocked tip, injected volume (ul); NaN past the FE's range (flagged)."""
        z = z_value(level)
        p = number_array(pressures_pa, "pressures_pa", "Pa")
        if (p < 0).any():
            raise InputError("pressures_pa", f"negative pressure {p.min():g} Pa",
                             "pressures >= 0 Pa")
        point = locate(design, reduced=True)
        if self.balance_model_for(point) is not None:
            return self._balance_answer(design, point, "pressure", p, level)
        pe, cb = self.curve_band(point, z, volume_band=False)
        p_red = p / point.pressure_scale
        p_lim = cb.limit_pressure_pa
        past = p_red > p_lim * (1 + 1e-12)
        p0 = _with_origin(cb.pressure_pa)
        # at most the range's end: where the monotone p(theta) is flat at the top, the
        # limit pressure reads a fine angle past it (90.04 deg for a 90-deg stop)
        angle = np.minimum(np.interp(p_red, p0, ANGLES0), cb.limit_angle_deg)
        upper = np.interp(p_red, _with_origin(cb.pressure_lower_pa), ANGLES0)
        lower = np.interp(p_red, _with_origin(cb.pressure_upper_pa), ANGLES0)
        lower, upper = floored_band(angle, lower, upper)
        volume = (np.interp(angle, ANGLES0, _with_origin(cb.volume_ul))
                  * point.length_scale**3)
        for a in (angle, upper, lower, volume):
            a[past] = np.nan
        if pe.sign < 0:
            angle, lower, upper = -angle, -upper, -lower
        angle, lower, upper = one_signed(angle, lower, upper, pe.sign)
        force = self._force(pe, cb, point, p_red, z)
        validity = self._validity(pe, cb, point, p, past, force)
        validity["fe_limit_volume_ul"] = float(
            np.interp(cb.limit_angle_deg, ANGLES0, _with_origin(cb.volume_ul))
            * point.length_scale**3)
        lower, upper = band_within_fe(lower, upper, cb.limit_angle_deg, validity)
        return self._prediction(design, point, p, (angle, lower, upper), level, validity,
                                force, volume)

    def _prediction(self, design: Design, point: BoxPoint, pressure_pa: np.ndarray,
                    band: tuple[np.ndarray, np.ndarray, np.ndarray], level: float,
                    validity: dict, force: tuple | None, volume_ul: np.ndarray) -> Prediction:
        """The answer by pressure: ``band`` is (angle, lower, upper) in deg."""
        angle, lower, upper = band
        return Prediction(design=design, pressure_pa=pressure_pa, angle_deg=angle,
                          lower_deg=lower, upper_deg=upper, level=level, validity=validity,
                          model=self.name, form="emulator", provenance=dict(self.provenance),
                          parameters={"pair": "/".join(point.pair),
                                      "stiffness_ratio": point.stiffness_ratio,
                                      "pressure_scale": point.pressure_scale,
                                      "length_scale": point.length_scale},
                          force_mn=None if force is None else force[0],
                          force_lower_mn=None if force is None else force[1],
                          force_upper_mn=None if force is None else force[2],
                          volume_ul=volume_ul)

    def predict_volume(self, design: Design, volumes_ul: object, level: float = 0.95,
                       band: bool = True) -> Prediction:
        """The syringe-pump view: angle (deg) with its band, chamber pressure (Pa) and the
        blocked-tip force at that pressure (mN) at each injected volume (ul, whole
        actuator), read off the emulated V(theta) and p(theta) of the same design; NaN
        past the FE's range (flagged). Under volume control the answer stays defined
        where p(theta) has a maximum: the pressure is the emulated one, falling past it
        (flag ``past_pressure_maximum``; ``surrogate.volume_control``). ``band=False``
        for a caller that reads no angle band (the calibration's tables): lower_deg and
        upper_deg are then NaN, and the band of V(theta) -- a GP variance per volume node,
        about half of a first query's cost -- is not computed (an answer of the balance
        model, whose band costs nothing more, keeps it)."""
        z = z_value(level)
        v = number_array(volumes_ul, "volumes_ul", "ul")
        if (v < 0).any():
            raise InputError("volumes_ul", f"negative volume {v.min():g} ul", "volumes >= 0 ul")
        point = locate(design, reduced=True)
        if self.balance_model_for(point) is not None:
            return self._balance_answer(design, point, "volume", v, level)
        pe, cb = self.curve_band(point, z, volume_band=band)   # serves both axes
        vm, vl, vh = self._volume_curves(cb, z)
        ls3 = point.length_scale**3
        v_red = v / ls3
        v_lim = float(np.interp(cb.limit_angle_deg, ANGLES0, vm))
        past = v_red > v_lim * (1 + 1e-12)
        answer = by_volume(v_red, vm, _with_origin(cb.pressure_raw_pa), ANGLES0,
                           rel_drop=EMULATED_PRESSURE_DROP)
        angle = answer.angle_deg
        if band:
            upper = np.interp(v_red, vl, ANGLES0)
            lower = np.interp(v_red, vh, ANGLES0)
            lower, upper = floored_band(angle, lower, upper)
        else:
            lower, upper = np.full_like(angle, np.nan), np.full_like(angle, np.nan)
        p_red = answer.pressure_pa
        pressure = p_red * point.pressure_scale
        for a in (angle, upper, lower, pressure, p_red):
            a[past] = np.nan
        if pe.sign < 0:
            angle, lower, upper = -angle, -upper, -lower
        angle, lower, upper = one_signed(angle, lower, upper, pe.sign)
        force = self._force(pe, cb, point, p_red, z)
        # pressure is NaN at the volumes past the range: no force is asked there
        validity = self._validity(pe, cb, point, pressure, past, force, "volume")
        if past.any():
            validity["messages"][0] = (
                f"{int(past.sum())} volume(s) above {v_lim * ls3:.1f} ul are past the FE's "
                f"range for this design, which ends at {pe.sign * cb.limit_angle_deg:.1f} "
                f"deg ({cb.stop_reason}): no angle is given there")
        validity["fe_limit_volume_ul"] = v_lim * ls3
        lower, upper = band_within_fe(lower, upper, cb.limit_angle_deg, validity)
        beyond = answer.past_maximum & ~past
        if beyond.any():
            p_max = answer.maximum_pressure_pa * point.pressure_scale
            validity["flags"].append("past_pressure_maximum")
            validity["messages"].append(
                f"{int(beyond.sum())} volume(s) above {answer.maximum_volume_ul * ls3:.2f} ul "
                f"are past the pressure maximum ({p_max:.0f} Pa at "
                f"{answer.maximum_angle_deg:.1f} deg): under volume control the angle keeps "
                "rising while the pressure falls; a pressure source would snap through here")
            validity["pressure_maximum_pa"] = p_max
            validity["pressure_maximum_volume_ul"] = answer.maximum_volume_ul * ls3
        return Prediction(design=design, pressure_pa=pressure, angle_deg=angle,
                          lower_deg=lower, upper_deg=upper, level=level, validity=validity,
                          model=self.name, form="emulator", provenance=dict(self.provenance),
                          parameters={"pair": "/".join(point.pair)},
                          force_mn=None if force is None else force[0],
                          force_lower_mn=None if force is None else force[1],
                          force_upper_mn=None if force is None else force[2],
                          volume_ul=v)

    def _balance_answer(self, design: Design, point: BoxPoint, axis: str, x: np.ndarray,
                        level: float) -> Prediction:
        """The answer at the stiffness balance (``balance``): the signed angle with its band
        at each pressure (``axis`` "pressure", Pa) or injected volume ("volume", ul), up to
        the volume stop of the FE curves there; the blocked-tip force of the per-direction
        force model where the design has a direction, none at the balance itself."""
        model = self.balance_models[point.group]
        z = z_value(level)
        ls3 = point.length_scale**3
        nodes = model.nodes(point.coordinates())
        if axis == "pressure":
            angle, lower, upper, v_red = model.by_pressure(nodes, x / point.pressure_scale, z)
            pressure, volume = x.copy(), v_red * ls3
        else:
            v_red = x / ls3
            angle, lower, upper, p_red = model.by_volume(nodes, v_red, z)
            pressure, volume = p_red * point.pressure_scale, x.copy()
        lower, upper = floored_band(angle, lower, upper)
        v_limit, stop, pressure_stopped, limit_pa, limit_angle = self._balance_limits(
            model, nodes, point, z)
        past = v_red > v_limit * (1 + 1e-12)
        for a in (angle, lower, upper, pressure if axis == "volume" else volume):
            a[past] = np.nan
        force = pair = None
        try:        # a design with a direction keeps the blocked-tip force it had
            pair = self.curve_band(point, z, volume_band=False)
            force = self._force(*pair[:2], point, pressure / point.pressure_scale, z)
            for f in force or ():
                f[past] = np.nan
        except InputError:
            pass    # at the balance itself: no direction, no force model
        flags = ["near_stiffness_balance"]
        messages = [balance_message(model.designs)
                    + ("no force is emulated where the direction is undecided; "
                       if force is None else "the blocked-tip force is the force model's "
                       "for the direction the design bends; ")
                    + "an FE solve (POST /v1/solve) gives this design's own curve"]
        if force is not None and pair is not None:
            self._force_flags(*pair, point, np.where(past, np.nan, pressure), force, flags,
                              messages, f"{axis}(s)")
        if past.any():
            flags.insert(0, "past_fe_range")
            if pressure_stopped:
                flags.insert(1, "past_fe_pressure_stop")
            what = (f"pressure(s) above {limit_pa:.0f} Pa" if axis == "pressure" else
                    f"volume(s) above {v_limit * ls3:.1f} ul")
            messages.insert(0, f"{int(past.sum())} {what} are past the FE's range for this "
                               f"design, which ends at {limit_angle:.1f} deg ({stop}): no "
                               "angle is given there")
        # in_domain: the design is in the box (a design outside is refused); the points
        # past the range have their own flag
        validity: dict[str, object] = {
            "in_domain": True, "flags": flags, "messages": messages,
            "fe_limit_pa": limit_pa, "fe_limit_angle_deg": limit_angle,
            "fe_stop_reason": stop, "fe_limit_volume_ul": v_limit * ls3}
        # the curves here end at the volume stop, short of the FE's angle stop: no band past it
        lower, upper = band_within_fe(lower, upper, SolverSettings().max_angle_deg, validity)
        return self._prediction(design, point, pressure, (angle, lower, upper), level,
                                validity, force, volume)

    def _balance_limits(self, model: BalanceModel, nodes: tuple, point: BoxPoint, z: float
                        ) -> tuple[float, str, bool, float, float]:
        """The FE's range of a design the balance model answers: (its end as a reduced
        injected volume in ul, why it ends there, whether that is the FE's pressure stop,
        the chamber pressure in Pa and the signed angle in deg there)."""
        v_stop = min(float(VOLUME_NODES_UL[-1]),
                     BALANCE_VOLUME_MARGIN * SolverSettings().max_volume_ul
                     / point.length_scale**3)
        # the group's early-ended curves (the same in both directions' pair emulators)
        pe = self.pairs.get(point.group + "+") or self.pairs.get(point.group + "-")
        cap_ul = (None if pe is None else
                  pe.end_volume_cap_ul(pe.failed_distances(point.coordinates())))
        cap_reason = None
        if cap_ul is not None and cap_ul < v_stop:
            v_stop = cap_ul
            cap_reason = end_volume_reason(cap_ul * point.length_scale**3)
        v_limit, stop, pressure_stopped = self._balance_range_end(
            model, nodes, v_stop, z, point.pressure_scale, cap_reason)
        at_limit = model.by_volume(nodes, np.array([v_limit]), z)
        top = SolverSettings().max_angle_deg
        return (v_limit, stop, pressure_stopped, float(at_limit[3][0]) * point.pressure_scale,
                float(np.clip(at_limit[0][0], -top, top)))

    def _balance_inverse(self, design: Design, point: BoxPoint, angles: np.ndarray,
                         level: float) -> InversePrediction:
        """The inverse near the stiffness balance, from the balance model that answers by
        pressure and by volume there (``BalanceModel.volumes_for``): for each signed
        angle the chamber pressure (Pa) and injected volume (ul) where the model's angle
        first reaches it, with their bands; none where it is not reached within the FE's
        range (the volume stop, or the angle stop). The per-direction GPs' inverse, used
        here until 2026-12-06, gave 28.5 and 125 ul for 10 and 30 deg where the FE needs
        21.1 and 85.4 ul, and the answer by those volumes read 13.8 and 32.7 deg (an
        audit of the thirty-seventh session)."""
        model = self.balance_models[point.group]
        z = z_value(level)
        ls3, s = point.length_scale**3, point.pressure_scale
        nodes = model.nodes(point.coordinates())
        v_limit, stop, pressure_stopped, limit_pa, limit_angle = self._balance_limits(
            model, nodes, point, z)
        volumes, pressures = model.volumes_for(nodes, angles, v_limit, z)
        validity: dict[str, object] = {
            "in_domain": True, "flags": ["near_stiffness_balance"],
            "messages": [balance_message(model.designs) + "the injected volume and chamber "
                         "pressure are where its angle first reaches each target; an FE "
                         "solve (POST /v1/solve) gives this design's own curve"],
            "fe_limit_pa": limit_pa, "fe_limit_angle_deg": limit_angle,
            "fe_stop_reason": stop, "fe_limit_volume_ul": v_limit * ls3}
        unreached = np.isnan(volumes[0])
        if unreached.any():
            validity["flags"].insert(0, "past_fe_range")
            if pressure_stopped:
                validity["flags"].insert(1, "past_fe_pressure_stop")
            validity["messages"].insert(
                0, f"no pressure for {int(unreached.sum())} angle(s) not reached within the "
                   f"FE's range, which ends at {limit_angle:.1f} deg for this design ({stop})")
        return InversePrediction(design=design, angle_deg=angles, pressure_pa=pressures[0] * s,
                                 lower_pa=pressures[1] * s, upper_pa=pressures[2] * s,
                                 level=level, validity=validity, model=self.name,
                                 form="emulator", provenance=dict(self.provenance),
                                 volume_ul=volumes[0] * ls3, volume_lower_ul=volumes[1] * ls3,
                                 volume_upper_ul=volumes[2] * ls3)

    @staticmethod
    def _balance_range_end(model: BalanceModel, nodes: tuple, v_limit: float, z: float,
                           pressure_scale: float, volume_reason: str | None = None
                           ) -> tuple[float, str, bool]:
        """Where the FE's range ends for a design the balance model answers (reduced
        volume, ul) and why: the volume stop, or the FE's angle stop or its pressure stop
        (FE_PRESSURE_STOP_PA, at ``pressure_scale``) where the balance model's mean
        reaches one first. Answered past 90 deg, a design near the balance with a stiff
        body read 122 and 135 deg at 200 and 480 ul, its band cut to [90, 90] (an audit
        of the thirty-fifth session). The third item: whether it is the pressure stop.
        ``volume_reason``: why the range ends at ``v_limit`` when that is not the volume
        stop (``end_volume_reason``)."""
        top = SolverSettings().max_angle_deg
        grid = np.linspace(0.0, v_limit, 241)[1:]
        angle, _, _, p_red = model.by_volume(nodes, grid, z)
        ends = []   # (volume, why, pressure stop?) of each stop reached before the volume stop
        for x, stop, why in (
                (np.abs(angle), top, f"the FE's angle stop ({top:g} deg, "
                 "SolverSettings.max_angle_deg), which the balance model's curve reaches "
                 "before the volume stop"),
                (p_red * pressure_scale, FE_PRESSURE_STOP_PA, None)):
            v_end = float(first_reach(grid, x, np.array([stop]))[0])
            if np.isfinite(v_end):
                ends.append((v_end, why or pressure_stop_reason(
                    float(np.nanmax(p_red)) * pressure_scale), why is None))
        if not ends:
            return v_limit, volume_reason or (
                f"the FE's volume stop ({SolverSettings().max_volume_ul:g} ul, "
                "SolverSettings.max_volume_ul), where the FE curves near the balance end"
            ), False
        return min(ends)

    @staticmethod
    def _volume_curves(cb: CurveBand, z: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """V(theta) on ANGLES0 (reduced, ul): mean and the band's low and high curves."""
        return tuple(_with_origin(volume_shape(c))  # type: ignore[return-value]
                     for c in node_curves(cb.volume_log_mean, cb.volume_log_sd, z))

    def _force(self, pe: PairEmulator, cb: CurveBand, point: BoxPoint, p_red: np.ndarray,
               z: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Blocked-tip force (mN) with its band: F = p x (F/p emulated at the pressure
        nodes, linear between them), F scaling with s_membrane x length_scale^2."""
        if pe.force is None:
            return None
        mean, var = self._memo.get_or_make(  # type: ignore[attr-defined]
            ("force", pe.pair, cb.coordinates.tobytes()),
            lambda: pe.force.predict(cb.coordinates))
        sd = np.sqrt(var) * pe.force_sd_scales(cb.blocked_mean_pa)
        scale = point.pressure_scale * point.length_scale**2
        past = p_red > pe.force_end_pa(cb.limit_pressure_pa, cb.blocked_end_pa) * (1 + 1e-12)
        pm, pl, pu = cb.force_reference or (cb.pressure_pa, cb.pressure_lower_pa,
                                            cb.pressure_upper_pa)
        angle = np.interp(p_red, _with_origin(pm), ANGLES0)
        angle_hi = np.interp(p_red, _with_origin(pl), ANGLES0)
        angle_lo = np.interp(p_red, _with_origin(pu), ANGLES0)
        out = [scale * f for f in pe.force_reduced(mean, sd, cb.node_mean, p_red, angle,
                                                    angle_lo, angle_hi, z)]
        for f in out:
            f[past] = np.nan
        out = list(one_signed(*out, pe.sign))   # the blocked tip pushes the way it bends
        lo, hi = out[1], out[2]
        # no force where its band is wider than FORCE_BAND_LIMIT x the force itself:
        # the group's few blocked-tip designs do not back a number there
        unbacked = ~force_backed(out[0], lo, hi) & np.isfinite(out[0])
        return (np.where(unbacked, np.nan, out[0]), np.where(unbacked, np.nan, lo),
                np.where(unbacked, np.nan, hi))

    def random_design_coverage(self, pair: str, axis: str, near: bool) -> dict | None:
        """How well the bands of group ``pair`` (``axis`` "pressure" or "volume", designs
        near an early-ended curve or not) covered the FE curves of random designs after
        the second calibration: {"coverage", "points", "curves"}, or None (files before
        2026-12-04, or no such points)."""
        cal = self.report.get("random_design_calibration") or {}
        cell = ((cal.get("group_coverage_after") or {}).get(pair) or {}).get(axis) or {}
        found = cell.get("near" if near else "far")
        return found if found and found.get("coverage") is not None else None

    def _undercover(self, pe: PairEmulator, cb: CurveBand, axis: str
                    ) -> tuple[str, str] | None:
        """The flag and message when this design's group and side covered too little."""
        near = cb.failed_distance < NEAR_FAILED_RADIUS
        cell = self.random_design_coverage(pe.pair, axis, near)
        if (cell is None or cell["points"] < UNDERCOVER_MIN_POINTS
                or cell["coverage"] >= UNDERCOVER_LEVEL):
            return None
        where = "near" if near else "away from"
        return ("band_undercovers_random_designs",
                f"on FE curves of random designs of this group {where} curves that ended "
                f"early ({cell['curves']} curves, {cell['points']} points), the band by "
                f"{axis} covered only {100 * cell['coverage']:.0f} % of the FE's points, "
                "against the 95 % it states: the emulator is off by more than its band "
                "says here; an FE solve (POST /v1/solve) gives this design's own curve")

    def _validity(self, pe: PairEmulator, cb: CurveBand, point: BoxPoint, p: np.ndarray,
                  past: np.ndarray, force: object, axis: str = "pressure"
                  ) -> dict[str, object]:
        flags: list[str] = []
        messages: list[str] = []
        fe_limit_pa = cb.limit_pressure_pa * point.pressure_scale
        limit_deg = pe.sign * cb.limit_angle_deg        # signed, as the design's angles
        if past.any():
            flags.append("past_fe_range")
            messages.append(
                f"{int(past.sum())} pressure(s) above {fe_limit_pa:.0f} Pa are past the FE's "
                f"range for this design, which ends at {limit_deg:.1f} deg "
                f"({cb.stop_reason}): no angle is given there; an FE solve of this "
                "design (POST /v1/solve; its max_angle_deg and max_volume_ul can be raised) "
                "tells where its curve really ends")
            if cb.pressure_stopped:
                flags.append("past_fe_pressure_stop")
        near = cb.failed_distance
        if near < NEAR_FAILED_RADIUS:
            flags.append("near_early_ended_fe_curves")
            messages.append(
                f"a database design {near:.2f} away (unit cube; {NEAR_FAILED_RADIUS:g} or "
                "less counts as near) has an FE curve that ended early (the volume stop, "
                "where the balloon grows more than the actuator bends, or a Newton "
                "failure): there the FE's response changes abruptly and the emulator is "
                "least reliable, its error on random designs two to three times that "
                "elsewhere and its band widened to match (docs/surrogate.md); an FE solve "
                "(POST /v1/solve) gives this design's own curve")
        under = self._undercover(pe, cb, axis)
        if under is not None:
            flags.append(under[0])
            messages.append(under[1])
        if force is not None:
            self._force_flags(pe, cb, point, p, force, flags, messages, f"{axis}(s)")
        # in_domain: the design is in the box (a design outside is refused before this);
        # the points past the FE's range have their own flag, past_fe_range
        return {"in_domain": True, "flags": flags, "messages": messages,
                "fe_limit_pa": fe_limit_pa, "fe_limit_angle_deg": limit_deg,
                "fe_stop_reason": cb.stop_reason}

    @staticmethod
    def _force_flags(pe: PairEmulator, cb: CurveBand, point: BoxPoint, p: np.ndarray,
                     force: tuple, flags: list[str], messages: list[str],
                     points: str = "pressure(s)") -> None:
        """Append why the force is withheld at some of the chamber pressures ``p`` (Pa;
        NaN where the angle itself is past the range): its band too wide within the
        force's range, or past that range (``force_past_fe_range``). ``points`` names the
        points as the question asked them ("pressure(s)", "volume(s)")."""
        f_end = pe.force_end_pa(cb.limit_pressure_pa, cb.blocked_end_pa)
        f_lim = f_end * point.pressure_scale
        within = p <= f_lim * (1 + 1e-12)        # False at NaN: past the angle's range
        unbacked = np.isnan(force[0]) & within
        if unbacked.any():
            flags.append("force_band_too_wide")
            messages.append(f"no force at {int(unbacked.sum())} {points}: its band "
                            f"is wider than {FORCE_BAND_LIMIT:g} x the force there (too "
                            "few blocked-tip FE curves near this design; an FE solve "
                            "with tip = blocked gives it)")
        if not within.all():
            flags.append("force_past_fe_range")
            if f_end >= cb.blocked_end_pa * (1 - 1e-12):
                why = pe.blocked_range.reason(  # type: ignore[union-attr]
                    cb.coordinates, cb.blocked_mean_pa, cb.blocked_end_pa,
                    point.pressure_scale)
            elif f_end >= pe.force_limit_pa * (1 - 1e-12):
                why = "the end of the blocked-tip FE curves"
            else:
                why = ("the end of this design's free-tip range (the force is "
                       "emulated as its ratio to the free tip's angle at the same "
                       "pressure)")
            messages.append(f"force is given up to {f_lim:.0f} Pa, {why}")

    def inverse(self, design: Design, angle_deg: object, level: float = 0.95
                ) -> InversePrediction:
        """Chamber pressure (Pa) and injected volume (ul) that give each angle (deg), each
        with a band at ``level``."""
        z = z_value(level)
        ang = number_array(angle_deg, "angle_deg", "deg")
        point = locate(design, reduced=True)
        if self.balance_model_for(point) is not None:
            return self._balance_inverse(design, point, ang, level)
        pe, cb = self.curve_band(point, z)
        signed = ang * pe.sign
        if (signed < 0).any():
            bad = float(ang[signed < 0][0])
            direction = "positive" if pe.sign > 0 else "negative"
            raise InputError("angle_deg", f"{bad:g} deg: this design bends the other way",
                             f"{direction} angles (sign of the pair's bending)")
        # past the FE's range: no number (null, flagged), as a prediction by pressure
        past = signed > cb.limit_angle_deg + 1e-9
        s = point.pressure_scale
        p = np.interp(signed, ANGLES0, _with_origin(cb.pressure_pa)) * s
        lo = np.interp(signed, ANGLES0, _with_origin(cb.pressure_lower_pa)) * s
        hi = np.interp(signed, ANGLES0, _with_origin(cb.pressure_upper_pa)) * s
        vm, vl, vh = self._volume_curves(cb, z)
        ls3 = point.length_scale**3
        limit_deg = pe.sign * cb.limit_angle_deg        # signed, as the design's angles
        validity = {"in_domain": True, "flags": [], "messages": [],
                    "fe_limit_pa": cb.limit_pressure_pa * s,
                    "fe_limit_angle_deg": limit_deg, "fe_stop_reason": cb.stop_reason,
                    "fe_limit_volume_ul": float(np.interp(cb.limit_angle_deg, ANGLES0, vm)
                                                * ls3)}
        if past.any():
            validity["flags"].append("past_fe_range")
            if cb.pressure_stopped:
                validity["flags"].append("past_fe_pressure_stop")
            validity["messages"].append(
                f"no pressure for {int(past.sum())} angle(s) past the FE's range, which ends "
                f"at {limit_deg:.1f} deg for this design ({cb.stop_reason})")

        def answered(x: np.ndarray) -> np.ndarray:
            return np.where(past, np.nan, x)

        return InversePrediction(design=design, angle_deg=ang, pressure_pa=answered(p),
                                 lower_pa=answered(lo), upper_pa=answered(hi), level=level,
                                 validity=validity, model=self.name, form="emulator",
                                 provenance=dict(self.provenance),
                                 volume_ul=answered(np.interp(signed, ANGLES0, vm) * ls3),
                                 volume_lower_ul=answered(np.interp(signed, ANGLES0, vl) * ls3),
                                 volume_upper_ul=answered(np.interp(signed, ANGLES0, vh) * ls3))

    def evaluate_designs(self, designs: list[Design], pressure_pa: float,
                         angle_deg: float | None, level: float = 0.95) -> dict[str, np.ndarray]:
        """Many designs at once (inverse design): |angle| (deg) with its band at
        ``pressure_pa``, and the pressure needed for |``angle_deg``| with its band (NaN
        past the FE's range), and which way each bends (``sign``: +1 away from the
        membrane, -1 towards it, 0 near a balance, where no answer is given); arrays in
        the order of ``designs``. Raises InputError for a design outside the box."""
        z = z_value(level)
        points = [locate(d, reduced=True) for d in designs]
        coords = np.array([pt.coordinates() for pt in points])
        out = {k: np.full(len(designs), np.nan) for k in (
            "angle", "angle_lo", "angle_hi", "needed", "needed_lo", "needed_hi", "force",
            "force_lo", "force_hi")}
        out["sign"] = np.zeros(len(designs))
        by_pair: dict[str, list[int]] = {}
        for key, idx in self._signed_groups(points, coords).items():
            if key in self.pairs:
                by_pair[key] = idx
        for key, idx in by_pair.items():
            pe = self.pairs[key]
            out["sign"][idx] = 1.0 if key.endswith("+") else -1.0
            u = coords[idx]
            # the variance as a single query reads it: exact at variance_nodes, spread
            mean, var, ends, plain = (
                pe.curve_nodes_many(u, variance_of=self.variance_nodes)
                if pe.curves.per_output else pe.curve_nodes_many(u))
            if pe.curves.per_output:
                var = np.array([self.spread_variance(row) for row in var])
            scales = pe.band_scales(pe.nearest_failed(u))
            y, sd = mean[:, :N_NODES], np.sqrt(var[:, :N_NODES]) * scales[:, :N_NODES]
            curves = [np.maximum.accumulate(c, axis=1) for c in node_curves(y, sd, z)]
            fmean = fsd = None
            force_curves = curves
            if pe.force is not None:
                fmean, fvar = pe.force.predict_many(u)
                blocked_ends, blocked_means = pe.blocked_ends_pa(u)
                fsd = np.sqrt(fvar) * pe.force_sd_scales(blocked_means)
                if plain is not None:
                    # the force model's angle and band: the complete-curve GPs' (as
                    # curve_band)
                    p_mean, p_var = plain
                    if pe.curves.per_output:
                        p_var = np.array([self.spread_variance(np.concatenate((r, v)))
                                          for r, v in zip(p_var, var[:, N_NODES:],
                                                          strict=True)])
                    p_sd = np.sqrt(p_var[:, :N_NODES]) * scales[:, :N_NODES]
                    force_curves = [np.maximum.accumulate(c, axis=1)
                                    for c in node_curves(p_mean, p_sd, z)]
            volumes = emulated_volume_ul(mean[:, N_NODES:])
            for row, i in enumerate(idx):
                pt = points[i]
                limit = pe.fe_range(u[row], volumes[row], pt.length_scale, ends[row])[0]
                pm, pl, pu = (_with_origin(c[row]) for c in curves)
                at_stop = pressure_stop_angle(limit, ANGLES0, pm, pt.pressure_scale)
                limit = limit if at_stop is None else at_stop
                p_lim = float(np.interp(limit, ANGLES0, pm))
                q = pressure_pa / pt.pressure_scale
                if q <= p_lim:
                    out["angle"][i] = np.interp(q, pm, ANGLES0)
                    out["angle_lo"][i] = np.interp(q, pu, ANGLES0)
                    out["angle_hi"][i] = np.interp(q, pl, ANGLES0)
                if angle_deg is not None and abs(angle_deg) <= limit:
                    a = abs(angle_deg)
                    s = pt.pressure_scale
                    out["needed"][i] = np.interp(a, ANGLES0, pm) * s
                    out["needed_lo"][i] = np.interp(a, ANGLES0, pl) * s
                    out["needed_hi"][i] = np.interp(a, ANGLES0, pu) * s
                if fmean is not None and q <= pe.force_end_pa(p_lim, blocked_ends[row]):
                    scale = pt.pressure_scale * pt.length_scale**2
                    qa = np.array([q])
                    fm, fl, fu = (_with_origin(c[row]) for c in force_curves)
                    a, a_lo, a_hi = (np.interp(qa, c, ANGLES0) for c in (fm, fu, fl))
                    vals = [scale * float(v[0]) for v in one_signed(*pe.force_reduced(
                        fmean[row], fsd[row], mean[row], qa, a, a_lo, a_hi, z), pe.sign)]
                    lo_f, hi_f = vals[1], vals[2]
                    if force_backed(vals[0], lo_f, hi_f):
                        out["force"][i] = vals[0]
                        out["force_lo"][i], out["force_hi"][i] = lo_f, hi_f
        return out

    def nearest_records(self, design: Design, count: int = 3) -> list[str]:
        """Keys of the database curves nearest to ``design`` in the unit box."""
        point = locate(design, reduced=True)
        pe = self._pair(point)
        d = np.linalg.norm(pe.coordinates - point.coordinates(), axis=1)
        return [pe.keys[i] for i in np.argsort(d)[:count]]


def pairs_in_box() -> tuple[tuple[str, str], ...]:
    return PAIRS
