"""The surrogate: fitted families, prediction with bands and validity, one-design inverse.

    s.predict(design, pressures_pa)  -> Prediction        angle (deg) with a band
    s.inverse(design, angles_deg)    -> InversePrediction pressure (Pa) with a band
    s.family_parameters(design)      -> dict              the family's model parameters

Bands: see ``surrogate.exponential.bands``. The inverse is closed form, p = tau x with
x + c x^2 = ln(1 + angle / A); its band is the delta method on p (parameter covariance)
plus the residual scatter carried through dp/dangle.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from solver.design import Design
from solver.errors import InputError
from surrogate.band_level import z_value
from surrogate.errors import OutOfFamilyError
from surrogate.exponential import bands, equations
from surrogate.exponential.family import Family
from surrogate.exponential.paper_tables import SOURCE as PAPER_SOURCE
from surrogate.exponential.parameters import ModelParameters
from surrogate.exponential.validity import check, past_fe
from surrogate.exponential.volume_relation import VolumeRelation, check_volumes
from surrogate.predictor import (
    InversePrediction,
    Prediction,
    band_within_fe,
    number_array,
    one_signed,
)
from surrogate.volume_control import by_volume

# (database_path: files fitted before 2026-12-06 recorded the database's full path, which
# answers show by its name, service.convert.public_provenance)
_PROVENANCE_SUMMARY = ("format_version", "created_utc", "package_version", "git_commit",
                       "database_name", "database_path", "source")


@dataclass(frozen=True)
class Surrogate:
    """Fitted families plus where they came from. ``form`` None uses each family's
    default form; "exponential" (the paper's) or "extended" forces one."""

    name: str
    family_fits: tuple[Family, ...]
    provenance: dict = field(default_factory=dict)
    form: str | None = None
    report: dict = field(default_factory=dict)

    @property
    def families(self) -> list[dict]:
        """Plain view: body_material / membrane_material ids, T_mm, b_mm, h_mm, parameters
        (per form), default_form, force, domain."""
        out = []
        for f in self.family_fits:
            d = f.as_dict()
            d["body_material_parameters"] = d["body_material"]
            d["membrane_material_parameters"] = d["membrane_material"]
            d["body_material"] = f.body_material.id
            d["membrane_material"] = f.membrane_material.id
            out.append(d)
        return out

    def with_form(self, form: str | None) -> Surrogate:
        if form is not None and form not in equations.FORMS:
            raise InputError("form", f"unknown model form {form!r}", " | ".join(equations.FORMS))
        return replace(self, form=form)

    def covered_slices(self, pair: tuple[str, str]) -> list[dict[str, float]]:
        """The (T_mm, b_mm, h_mm) of every family of ``pair`` (preset materials): the
        exponential model answers only there (``surrogate.search.design_search``)."""
        from solver.materials import MATERIALS

        out = []
        for fam in self.family_fits:
            if (fam.body_material == MATERIALS.get(pair[0])
                    and fam.membrane_material == MATERIALS.get(pair[1])):
                _, _, T, b, h = fam.key
                out.append({"T_mm": T, "b_mm": b, "h_mm": h})
        return out

    def family_for(self, design: Design) -> Family:
        """The family covering ``design``; OutOfFamilyError (with the fix) otherwise."""
        for fam in self.family_fits:
            if fam.matches(design):
                return fam
        raise OutOfFamilyError(_out_of_family_message(self, design), design.family,
                               "a design of a fitted family: " + _covered(self))

    def _params(self, fam: Family, form: str | None) -> ModelParameters:
        form = form or self.form or fam.default_form
        if form not in fam.parameters:
            raise InputError("form", f"model form {form!r} was not fitted for {fam.label}",
                             " | ".join(fam.parameters))
        return fam.parameters[form]

    def _summary(self) -> dict:
        return {k: self.provenance[k] for k in _PROVENANCE_SUMMARY if k in self.provenance}

    def family_parameters(self, design: Design, form: str | None = None) -> dict[str, object]:
        """The family's model parameters for ``design``'s family, with A and tau at the
        design: a_deg_per_mm, a_t_pa, b_t_per_mm (and c), tau_form, covariance (of
        ``covariance_names``: log10 b_t in place of b_t), standard_errors,
        residual_sd_deg, residual_rel."""
        fam = self.family_for(design)
        par = self._params(fam, form)
        out: dict[str, object] = {n: v for n, v in zip(par.names, par.values, strict=True)}
        out.update(form=par.form, names=list(par.names), tau_form=equations.TAU_FORM,
                   covariance_names=list(par.covariance_names),
                   covariance=[list(r) for r in par.covariance],
                   standard_errors=par.standard_errors,
                   residual_sd_deg=par.residual_sd, residual_rel=par.residual_rel,
                   fixed=list(par.fixed), source=par.source,
                   A_deg=float(equations.amplitude_deg(par.theta, design.L_mm)),
                   tau_pa=float(equations.tau_pa(par.theta, design.t_mm)), family=fam.label)
        return out

    def _check_tau(self, par: ModelParameters, design: Design) -> None:
        if not float(equations.tau_pa(par.theta, design.t_mm)) > 0.0:
            t_min = 1.0 / par.theta[2]
            raise InputError("t_mm", f"t_mm = {design.t_mm:g} gives a non-positive pressure "
                             "constant tau", f"t_mm > {t_min:.3g} mm")

    def predict(self, design: Design, pressures_pa: object, level: float = 0.95,
                form: str | None = None) -> Prediction:
        """Angle (deg) at each pressure (Pa, >= 0) with a band at ``level``; force (mN)
        as well when the family has a force model."""
        fam = self.family_for(design)
        par = self._params(fam, form)
        self._check_tau(par, design)
        p = number_array(pressures_pa, "pressures_pa", "Pa")
        if (p < 0).any():
            raise InputError("pressures_pa", f"negative pressure {p.min():g} Pa",
                             "pressures >= 0 Pa (the model ignores suction)")
        # far past the FE's range (the calibration asks up to 1.6 x its largest reading,
        # 1.6e6 Pa) the exponential overflows to inf and its band to NaN: expected, and no
        # warning (`balloon calibrate` printed six, with source paths). Answers past the
        # range are NaN below; the calibration refuses infinite ones by name.
        with np.errstate(over="ignore", invalid="ignore"):
            m, lo, hi = bands.angle_band(par, design.L_mm, design.t_mm, p, level)
            force: tuple[np.ndarray | None, ...] = (None, None, None)
            if fam.force is not None:
                force = bands.angle_band(fam.force, design.L_mm, design.t_mm, p, level)
        validity = check(fam.domain, design, p, m)
        past = past_fe(fam.domain, p, m)   # no number past the FE's range
        m, lo, hi = (np.where(past, np.nan, x) for x in (m, lo, hi))
        # the family bends one way (the sign of A): no band across zero
        sign = 1.0 if float(equations.amplitude_deg(par.theta, design.L_mm)) > 0 else -1.0
        m, lo, hi = one_signed(m, lo, hi, sign)
        lo, hi = band_within_fe(lo, hi, fam.domain.angle_max_deg, validity)
        if fam.force is not None:
            force = one_signed(*(np.where(past, np.nan, f) for f in force), sign)
        volume = None
        if fam.volume is not None:   # the injected volume at the predicted angle
            nodes, vm, _, _ = _volume_table(fam.volume, design, level)
            a = np.abs(m)
            volume = np.where(a <= nodes[-1] * (1 + 1e-12), np.interp(a, nodes, vm), np.nan)
            validity["fe_limit_volume_ul"] = float(vm[-1])
        return self._prediction(design, par, p, (m, lo, hi), force, volume, level, validity)

    def predict_volume(self, design: Design, volumes_ul: object, level: float = 0.95,
                       form: str | None = None, band: bool = True) -> Prediction:
        """The syringe-pump view: angle (deg) with its band at each injected volume (ul,
        whole actuator), read off the family's FE-interpolated V(theta) (its band from
        that relation's held-out error, ``volume_relation``); the chamber pressure (Pa)
        is the exponential model's at that angle, the force (mN) the force model's at
        that pressure. NaN past the relation's largest angle or the family's FE range
        (flag ``past_fe_range``); ``past_pressure_maximum`` as for every model, though the
        exponential form's pressure never falls. InputError naming ``volumes_ul`` when the
        family has no relation (the paper preset; files of format version < 3). The band
        costs nothing here: given whatever ``band`` says (the emulator's signature)."""
        del band
        fam = self.family_for(design)
        if fam.volume is None:
            raise InputError("volumes_ul", _no_volume_message(self, fam),
                             'pressures_pa; by volume: model "emulator", or an exponential '
                             "model fitted from FE curves with volumes (`balloon fit`)")
        par = self._params(fam, form)
        self._check_tau(par, design)
        v = number_array(volumes_ul, "volumes_ul", "ul")
        check_volumes(v)
        nodes, vm, vlo, vhi = _volume_table(fam.volume, design, level)
        sign = 1.0 if float(equations.amplitude_deg(par.theta, design.L_mm)) > 0 else -1.0
        p_nodes = equations.pressure_pa(par.theta, design.L_mm, design.t_mm, sign * nodes)
        answer = by_volume(v, vm, p_nodes, nodes)
        ang = sign * answer.angle_deg
        p = equations.pressure_pa(par.theta, design.L_mm, design.t_mm, ang)
        hi_a, lo_a = (sign * np.interp(v, vv, nodes) for vv in (vlo, vhi))
        ang, lower, upper = one_signed(ang, np.fmin(lo_a, hi_a), np.fmax(lo_a, hi_a), sign)
        validity = check(fam.domain, design, np.nan_to_num(p), np.nan_to_num(ang))
        flags, messages = _lists(validity)
        past = answer.past_end | past_fe(fam.domain, p, ang)
        ang, lower, upper, p = (np.where(past, np.nan, x) for x in (ang, lower, upper, p))
        force: tuple[np.ndarray | None, ...] = (None, None, None)
        if fam.force is not None:
            force = one_signed(*(np.where(past, np.nan, f) for f in bands.angle_band(
                fam.force, design.L_mm, design.t_mm, np.nan_to_num(p), level)), sign)
        v_lim = float(vm[-1])
        validity["fe_limit_volume_ul"] = v_lim
        if answer.past_end.any():
            if "past_fe_range" not in flags:
                flags.append("past_fe_range")
            messages.append(
                f"{int(answer.past_end.sum())} volume(s) above {v_lim:.1f} ul are past the "
                f"family's FE volumes for this design ({nodes[-1]:.1f} deg, the smallest "
                "largest angle of its FE curves): no angle is given")
        beyond = answer.past_maximum & ~past
        if beyond.any() and answer.maximum_pressure_pa is not None:
            flags.append("past_pressure_maximum")
            messages.append(
                f"{int(beyond.sum())} volume(s) are past the pressure maximum "
                f"({answer.maximum_pressure_pa:.0f} Pa): under volume control the angle keeps "
                "rising while the pressure falls")
        return self._prediction(design, par, p, (ang, lower, upper), force, v, level,
                                validity)

    def _prediction(self, design: Design, par: ModelParameters, p: np.ndarray,
                    angle: tuple[np.ndarray, np.ndarray, np.ndarray],
                    force: tuple[np.ndarray | None, ...], volume: np.ndarray | None,
                    level: float, validity: dict) -> Prediction:
        return Prediction(design=design, pressure_pa=p, angle_deg=angle[0],
                          lower_deg=angle[1], upper_deg=angle[2], level=level,
                          validity=validity, model=self.name, form=par.form,
                          provenance=self._summary(),
                          parameters={n: v for n, v in zip(par.names, par.values, strict=True)},
                          force_mn=force[0], force_lower_mn=force[1], force_upper_mn=force[2],
                          volume_ul=volume)

    def inverse(self, design: Design, angle_deg: object, level: float = 0.95,
                form: str | None = None) -> InversePrediction:
        """Pressure (Pa) that gives each angle (deg), closed form, with a band."""
        fam = self.family_for(design)
        par = self._params(fam, form)
        self._check_tau(par, design)
        ang = number_array(angle_deg, "angle_deg", "deg")
        p, half = bands.pressure_band(par, design.L_mm, design.t_mm, ang, level)
        bad = ~np.isfinite(p)
        if bad.any():
            A = float(equations.amplitude_deg(par.theta, design.L_mm))
            top = float(equations.max_angle_deg(par.theta, design.L_mm, design.t_mm))
            sign = "positive" if A > 0 else "negative"
            allowed = f"{sign} angles (A = {A:.4g} deg)"
            if np.isfinite(top):
                allowed += f" of magnitude below {top:.4g} deg"
            raise InputError("angle_deg", f"{ang[bad][0]:g} deg is not reachable by this "
                             "design", allowed)
        validity = check(fam.domain, design, p, ang)
        flags, messages = _lists(validity)
        past = past_fe(fam.domain, p, ang)   # no number past the FE's range
        p, lower, upper = (np.where(past, np.nan, x)
                           for x in (p, np.maximum(p - half, 0.0), p + half))
        volumes: tuple[np.ndarray | None, ...] = (None, None, None)
        if fam.volume is not None:   # the injected volume that reaches each angle, band
            nodes, vm, vlo, vhi = _volume_table(fam.volume, design, level)
            a = np.abs(ang)
            out = a > nodes[-1] * (1 + 1e-12)
            volumes = tuple(np.where(past | out, np.nan, np.interp(a, nodes, vv))
                            for vv in (vm, vlo, vhi))
            if out.any():
                if "past_fe_range" not in flags:   # an angle past the family's FE range
                    flags.append("past_fe_range")
                messages.append(
                    f"no volume above {nodes[-1]:.1f} deg, the smallest largest angle of the "
                    "family's FE curves")
        return InversePrediction(design=design, angle_deg=ang, pressure_pa=p,
                                 lower_pa=lower, upper_pa=upper,
                                 level=level, validity=validity,
                                 model=self.name, form=par.form, provenance=self._summary(),
                                 volume_ul=volumes[0], volume_lower_ul=volumes[1],
                                 volume_upper_ul=volumes[2])


def _lists(validity: dict) -> tuple[list[str], list[str]]:
    """The validity's flag and message lists (appended to in place)."""
    return validity["flags"], validity["messages"]


def _volume_table(rel: VolumeRelation, design: Design, level: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(|angle| nodes with 0, V, V low, V high) of the design (deg, ul) at ``level``."""
    vm, vlo, vhi = rel.band_curves_ul(design.L_mm, design.t_mm, z_value(level))
    return np.concatenate([[0.0], rel.angle_nodes_deg]), vm, vlo, vhi


def _no_volume_message(s: Surrogate, fam: Family) -> str:
    why = ("the paper publishes no volumes" if s.provenance.get("source") == PAPER_SOURCE
           else "its file predates format version 3, or its FE curves held no volumes; "
           "refit it with `balloon fit --db DB -o FILE`")
    return (f"model {s.name!r} answers by pressure only: no pressure-volume relation for "
            f"{fam.label} ({why})")


def _covered(s: Surrogate) -> str:
    """The fitted families in words (material pair, T, b, h), "none" without any."""
    return "; ".join(f.label for f in s.family_fits) or "none"


def _out_of_family_message(s: Surrogate, design: Design) -> str:
    body, membrane, T, b, h = design.family
    covered = _covered(s)
    same_ids = [f for f in s.family_fits if f.key == design.family]
    note = (" (a family with these material ids exists, but its Ogden parameters differ)"
            if same_ids else "")
    return (f"surrogate '{s.name}' has no fitted family for body {body}, membrane "
            f"{membrane}, T_mm={T:g}, b_mm={b:g}, h_mm={h:g}{note}; covered: {covered}. "
            f"To add it, append to the precompute grid a sweep "
            f"[[sweep]] pairs = [[\"{body}\", \"{membrane}\"]], T_mm = {T:g}, b_mm = {b:g}, "
            f"h_mm = {h:g}, with at least two L_mm and two t_mm values, run `balloon "
            "precompute GRID.toml --db DB`, then `balloon fit --db DB -o surrogate.json`")
