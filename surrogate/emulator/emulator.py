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

The modules: ``pair_emulator`` (one group and direction's GPs and failed curves),
``node_curves`` and ``volume_curve`` (curves on the fine angles from node values),
``fe_range`` (where a design's range ends and why), ``curve_band`` (a design's curve with
its band), ``force_answer`` and ``validity`` (the force and the answer's flags and
messages), ``balance_answer`` (the stiffness balance), ``many_designs`` (the batch of the
inverse design); ``Emulator`` here locates a design and answers by pressure, by volume
and backwards.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from solver.design import Design
from solver.design_space import PAIRS, BoxPoint, locate
from solver.errors import InputError
from surrogate.band_level import z_value
from surrogate.emulator import many_designs
from surrogate.emulator.balance import BalanceModel
from surrogate.emulator.balance_answer import (
    balance_answer,
    balance_answers,
    balance_inverse,
    bending_direction,
)
from surrogate.emulator.curve_band import CurveBand, design_curve_band, volume_curves
from surrogate.emulator.design_memo import DesignMemo
from surrogate.emulator.fe_range import pressure_stop_angle
from surrogate.emulator.features import FINE_ANGLES_DEG, N_NODES
from surrogate.emulator.force_answer import blocked_force
from surrogate.emulator.node_curves import ANGLES0, _with_origin, floored_band
from surrogate.emulator.pair_emulator import (
    FAILED_RADIUS,
    NEAR_FAILED_RADIUS,
    PairEmulator,
    ended_at_newton_failure,
)
from surrogate.emulator.validity import (
    UNDERCOVER_LEVEL,
    UNDERCOVER_MIN_POINTS,
    answer_validity,
    stretch_flag,
)
from surrogate.emulator.variance_nodes import FORMAT_7_NODES, spline, spread_variance
from surrogate.emulator.vector_gp import MEANS_ONLY, VectorGP
from surrogate.emulator.volume_answer import at_volumes, volumes_at_angles
from surrogate.emulator.volume_curve import (
    VOLUME_EXPONENT_FLOOR,
    VOLUME_FLOOR_FROM_DEG,
    angle_at_volume_deg,
    emulated_volume_ul,
    volume_shape,
)
from surrogate.predictor import (
    InversePrediction,
    Prediction,
    band_within_fe,
    number_array,
    one_signed,
    pressure_stop_reason,
)

# Emulator, and the names that tests and benchmarks import from here (defined in the
# modules above since this module was split, 2026-12-06)
__all__ = ["FAILED_RADIUS", "FINE_ANGLES_DEG", "N_NODES", "NEAR_FAILED_RADIUS",
           "UNDERCOVER_LEVEL", "UNDERCOVER_MIN_POINTS", "VOLUME_EXPONENT_FLOOR",
           "VOLUME_FLOOR_FROM_DEG", "Emulator", "angle_at_volume_deg", "emulated_volume_ul",
           "ended_at_newton_failure", "volume_shape"]


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
            if pe.range_model is not None:      # its sd, asked for near early ends only
                pe.emulated_end_deg(u)
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
        sign = float(bending_direction(m)[0])
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
            lambda: balance_answers(self, point.group, model, u))
        return model if answers else None

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
                     bending_direction(model.predict_many(
                         coords[idx], variance_of=MEANS_ONLY)[0][:, 0]))
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
        return pair_key, design_curve_band(self, self.pairs[pair_key], point, u, z, volume_band)

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
            return balance_answer(self, design, point, "pressure", p, level)
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
        force = blocked_force(self._memo, pe, cb, point, p_red, z)  # type: ignore[attr-defined]
        validity = answer_validity(self.report, pe, cb, point, p, past, force,
                                   answered_deg=np.abs(angle))
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
            return balance_answer(self, design, point, "volume", v, level)
        pe, cb = self.curve_band(point, z, volume_band=band)   # serves both axes
        ls3 = point.length_scale**3
        read = at_volumes(v / ls3, volume_curves(cb, z), _with_origin(cb.pressure_raw_pa),
                          cb.limit_angle_deg, band)
        v_lim, past, answer = read.limit_volume_ul, read.past, read.curve
        angle, lower, upper = read.angle_deg, read.lower_deg, read.upper_deg
        p_red = read.pressure_red_pa
        pressure = p_red * point.pressure_scale
        if pe.sign < 0:
            angle, lower, upper = -angle, -upper, -lower
        angle, lower, upper = one_signed(angle, lower, upper, pe.sign)
        force = blocked_force(self._memo, pe, cb, point, p_red, z)  # type: ignore[attr-defined]
        # pressure is NaN at the volumes past the range: no force is asked there
        validity = answer_validity(self.report, pe, cb, point, pressure, past, force,
                                   "volume", answered_deg=np.abs(angle))
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

    def inverse(self, design: Design, angle_deg: object, level: float = 0.95
                ) -> InversePrediction:
        """Chamber pressure (Pa) and injected volume (ul) that give each angle (deg), each
        with a band at ``level``."""
        z = z_value(level)
        ang = number_array(angle_deg, "angle_deg", "deg")
        point = locate(design, reduced=True)
        if self.balance_model_for(point) is not None:
            return balance_inverse(self, design, point, ang, level)
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
        vm, vl, vh = volume_curves(cb, z)
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
        stretch_flag(pe, cb, point, np.where(past, np.nan, signed), validity)

        def answered(x: np.ndarray) -> np.ndarray:
            return np.where(past, np.nan, x)

        # past the range: NaN (the same limit as ``past``, the volumes' own reading)
        volume, volume_lo, volume_hi = volumes_at_angles(np.abs(signed), (vm, vl, vh),
                                                         cb.limit_angle_deg)

        return InversePrediction(design=design, angle_deg=ang, pressure_pa=answered(p),
                                 lower_pa=answered(lo), upper_pa=answered(hi), level=level,
                                 validity=validity, model=self.name, form="emulator",
                                 provenance=dict(self.provenance),
                                 volume_ul=volume * ls3, volume_lower_ul=volume_lo * ls3,
                                 volume_upper_ul=volume_hi * ls3)

    def evaluate_designs(self, designs: list[Design], pressure_pa: float,
                         angle_deg: float | None, level: float = 0.95) -> dict[str, np.ndarray]:
        """Many designs at once (inverse design): ``many_designs.evaluate_designs``."""
        return many_designs.evaluate_designs(self, designs, pressure_pa, angle_deg, level)

    def evaluate_designs_by_volume(self, designs: list[Design], volume_ul: float,
                                   angle_deg: float, level: float = 0.95, band: bool = True
                                   ) -> dict[str, np.ndarray]:
        """Many designs at once by injected volume (a syringe pump's design target):
        ``many_designs.evaluate_designs_by_volume``."""
        return many_designs.evaluate_designs_by_volume(self, designs, volume_ul, angle_deg,
                                                       level, band)

    def nearest_records(self, design: Design, count: int = 3) -> list[str]:
        """Keys of the database curves nearest to ``design`` in the unit box."""
        point = locate(design, reduced=True)
        pe = self._pair(point)
        d = np.linalg.norm(pe.coordinates - point.coordinates(), axis=1)
        return [pe.keys[i] for i in np.argsort(d)[:count]]


def pairs_in_box() -> tuple[tuple[str, str], ...]:
    return PAIRS
