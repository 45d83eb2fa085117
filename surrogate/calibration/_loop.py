"""The loop: model as is -> recalibrated baseline -> candidate effects -> selection ->
residual structure. ``calibrate(obs, nominal)`` returns a ``Calibration`` whose
``report`` is the JSON report (docs/calibration.md describes every field).

Selection rule. A candidate set E (one effect, or a pair) is selectable when
1. every parameter is inside its physically plausible range;
2. every member is significant: its tested parameter is more than 3 standard errors from
   the value that switches it off, the standard error being clustered by curve (so that
   specimen-to-specimen scatter, which is shared along a curve, counts in full) -- a
   size the replicate scatter cannot explain;
3. BIC(E) < BIC(null) - 6 (strong evidence, penalising each parameter by ln n), the null
   being the recalibrated baseline, or for a parameter effect the baseline with its tau
   law pinned at the starting model;
4. cross-validated by curve, a structural set lowers the error of the recalibrated
   baseline; a set with a parameter effect (which re-expresses the recalibration with
   fewer numbers) is no more than 5 % worse than it;
5. it explains at least a quarter of the excess error of its null model over the noise floor,
   (cv_null^2 - cv_E^2) / (cv_null^2 - noise^2) >= 0.25, and that excess is itself real
   (cv_null > 1.118 x noise floor);
6. a pair earns its second term: BIC(pair) < BIC(each member alone) - 6, and its
   cross-validated error is below each member's alone (otherwise one member is riding
   along on the other's gain, or compensating the pinned tau law of a parameter effect).
Among selectable sets the lowest BIC wins. Confounded pairs: with one flow rate
hydraulic_resistance is pressure_offset (p0 = R Q): only pressure_offset is fitted, and the
interpretation gives both readings; with one thickness per family membrane_thickness_bias
is stiffness_scale (both only move tau at that thickness): only stiffness_scale is fitted.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from surrogate.calibration._checks import check_calibratable
from surrogate.calibration._data import Observations
from surrogate.calibration._effects import EFFECT_IDS, EFFECTS, R_CHANNEL
from surrogate.calibration._fit import FitResult, cross_validate, fit
from surrogate.calibration._forward import angle_model
from surrogate.calibration._noise import N_FLEX, noise_floor
from surrogate.calibration._structure import structure_test

Z_SIGNIFICANT = 3.0
DELTA_BIC = -6.0
PARAMETER_CV_TOLERANCE = 1.05
EXPLAINED_FRACTION = 0.25
EXCESS_RATIO = 1.118  # sqrt(1.25): the null's CV error must exceed the floor by 25 % in MSE
PAIRS_CROSS_VALIDATED = 4
REPORT_SCHEMA = "balloon.calibration.report/1"


@dataclass
class Calibration:
    """The result of the loop: the JSON ``report`` plus the fits (for plots and saving)."""

    report: dict
    obs: Observations
    nominal: np.ndarray
    before: FitResult
    after: FitResult
    residual_before_cv: np.ndarray = field(repr=False)
    residual_after_cv: np.ndarray = field(repr=False)


def _tested(eid: str) -> list[str]:
    names = []
    for p in EFFECTS[eid].parameters:
        if p.tested:
            names.append("inv_theta_max_per_deg" if p.name == "theta_max_deg" else p.name)
    return names


def _physical_params(f: FitResult) -> dict[str, dict]:
    out = {}
    sd = f.effect_sd()
    for eid in f.effects:
        for p in EFFECTS[eid].parameters:
            if p.name == "theta_max_deg":
                inv = f.values["inv_theta_max_per_deg"]
                value = 1.0 / inv if inv > 0 else math.inf
                s = sd["inv_theta_max_per_deg"] / inv**2 if inv > 0 else math.inf
            else:
                value, s = f.values[p.name], sd[p.name]
            lo, hi = p.plausible
            out[p.name] = {"value": _num(value), "sd": _num(s), "unit": p.unit,
                           "plausible_range": [lo, hi], "effect": eid,
                           "plausible": bool(lo <= value <= hi)}
    return out


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _nuisance(obs: Observations, f: FitResult) -> np.ndarray:
    """d angle / d log A and d angle / d log tau at every row (per-curve replicate scatter)."""
    h = 1e-4
    base = angle_model(obs, f.families, f.values)
    fa = f.families.copy()
    fa[:, 0] *= 1 + h
    ft = f.families.copy()
    ft[:, 1] *= 1 + h
    return np.column_stack([(angle_model(obs, fa, f.values) - base) / h,
                            (angle_model(obs, ft, f.values) - base) / h])


def calibrate(obs: Observations, nominal: np.ndarray, model: dict | None = None,
              folds: int = 5, progress=None) -> Calibration:
    """Run the loop on validated observations; ``nominal`` is (n_families, 4) starting
    parameters (a, a_t, b_t, c) in the order of ``obs.families``. Data the loop cannot
    use (one curve, pressures where the starting model is not finite) and ``folds`` < 2
    raise DataError/InputError (_checks.py); more folds than curves are reduced to the
    number of curves."""
    nominal = np.asarray(nominal, dtype=float)
    folds_requested = folds
    folds = check_calibratable(obs, nominal, folds)
    tick = progress or (lambda: None)
    y = obs.angle_deg
    rmse_model = float(np.sqrt(np.mean((angle_model(obs, nominal, {}) - y) ** 2)))
    noise = noise_floor(obs)

    fits: dict[tuple[tuple[str, ...], bool], FitResult] = {}
    cvs: dict[tuple[tuple[str, ...], bool], tuple[float, np.ndarray]] = {}

    def get_fit(effects: tuple[str, ...], pinned: bool = False) -> FitResult:
        key = (tuple(sorted(effects)), pinned or any(EFFECTS[e].kind == "parameter"
                                                      for e in effects))
        if key not in fits:
            fits[key] = fit(obs, key[0], nominal, pin_tau=key[1])
            tick()
        return fits[key]

    def get_cv(effects: tuple[str, ...], pinned: bool = False) -> tuple[float, np.ndarray]:
        f = get_fit(effects, pinned)
        key = (tuple(sorted(effects)), f.pinned)
        if key not in cvs:
            cvs[key] = cross_validate(obs, key[0], nominal, f, folds, f.pinned)
            tick()
        return cvs[key]

    base = get_fit(())
    rmse_before, resid_before = get_cv(())
    sigma2 = noise.rms_deg**2 if math.isfinite(noise.rms_deg) else base.sse / max(
        obs.n - base.k, 1)
    sigma = math.sqrt(sigma2)

    # Which singles can be fitted, and which are confounded.
    flows = np.unique(np.round(obs.flow_ul_s[np.isfinite(obs.flow_ul_s)], 6))
    multi_t = any(np.unique(obs.t_mm[obs.family == f]).size >= 2
                  for f in range(len(obs.families)))
    status: dict[str, dict] = {}
    for eid in EFFECT_IDS:
        e = EFFECTS[eid]
        missing = [c for c in e.needs if c == "time_s" and not obs.has_time
                   or c == "flow_ul_s" and not obs.has_flow]
        st: dict[str, Any] = {"applicable": not missing, "identifiable": True,
                              "confounded_with": None, "note": None}
        if missing:
            st["note"] = f"needs column {missing[0]}"
        elif eid == "hydraulic_resistance" and not obs.flow_varies:
            st.update(identifiable=False, confounded_with="pressure_offset",
                      note=f"one flow rate ({flows[0]:g} ul/s): exactly a pressure offset "
                      "p0 = R Q; measure at a second flow rate to separate them")
        elif eid == "membrane_thickness_bias" and not multi_t:
            st.update(identifiable=False, confounded_with="stiffness_scale",
                      note="one membrane thickness per family: a thickness bias and a "
                      "stiffness scale both only move tau at that thickness; "
                      "stiffness_scale is fitted for both")
        status[eid] = st
    singles = [e for e in EFFECT_IDS if status[e]["applicable"] and status[e]["identifiable"]]
    any_param = any(EFFECTS[e].kind == "parameter" for e in singles)
    rmse_pinned = get_cv((), pinned=True)[0] if any_param else math.nan

    def null_cv(effects: tuple[str, ...]) -> float:
        pinned = any(EFFECTS[e].kind == "parameter" for e in effects)
        return rmse_pinned if pinned else rmse_before

    for eid in singles:
        get_fit((eid,))
    pairs = [tuple(sorted(p)) for p in itertools.combinations(singles, 2)]
    for pair in pairs:
        get_fit(pair)
    pairs.sort(key=lambda p: get_fit(p).bic)
    evaluated = [(e,) for e in singles] + pairs[:PAIRS_CROSS_VALIDATED]

    candidates = []
    selectable = []
    for effects in evaluated:
        f = get_fit(effects)
        cv, _ = get_cv(effects)
        params = _physical_params(f)
        plausible = all(p["plausible"] for p in params.values())
        sd = f.effect_sd()
        z = {}
        for m in effects:
            for name in _tested(m):
                null = 0.0 if name == "inv_theta_max_per_deg" else EFFECTS[m].parameters[
                    [p.name for p in EFFECTS[m].parameters].index(name)].null
                z[name] = abs(f.values[name] - null) / sd[name] if sd[name] > 0 else math.inf
        significant = all(v > Z_SIGNIFICANT for v in z.values())
        delta_bic = f.bic - base.bic
        delta_bic_null = f.bic - get_fit((), pinned=f.pinned).bic
        cvn = null_cv(effects)
        excess = cvn**2 - sigma2
        explained = (cvn**2 - cv**2) / excess if excess > 0 else 0.0
        is_param = f.pinned
        cv_ok = cv <= rmse_before * PARAMETER_CV_TOLERANCE if is_param else cv < rmse_before
        reasons = []
        if not plausible:
            reasons.append("fitted values outside the plausible range")
        if not significant:
            reasons.append("gain within what replicate scatter explains")
        if delta_bic_null >= DELTA_BIC:
            reasons.append(f"delta BIC against its null {delta_bic_null:.1f} is not below "
                           f"{DELTA_BIC:g}")
        if not cv_ok:
            reasons.append("cross-validated error not better than the recalibrated baseline")
        if len(effects) > 1:
            alone = [(get_fit((m,)).bic, get_cv((m,))[0]) for m in effects]
            if f.bic >= min(b for b, _ in alone) + DELTA_BIC:
                reasons.append(f"delta BIC against its better member alone "
                               f"{f.bic - min(b for b, _ in alone):.1f} is not below "
                               f"{DELTA_BIC:g}")
            if cv >= min(c for _, c in alone):
                reasons.append("cross-validated error not better than a member alone")
        if cvn <= EXCESS_RATIO * sigma:
            reasons.append("its null model is already at the noise floor")
        elif explained < EXPLAINED_FRACTION:
            reasons.append(f"explains only {100 * explained:.0f} % of the excess error")
        ok = not reasons
        if ok:
            selectable.append((f.bic, effects))
        candidates.append({
            "effect": "+".join(effects), "effects": list(effects),
            "kind": "parameter" if is_param else "structural",
            "applicable": True, "identifiable": True, "confounded_with": None,
            "rmse_cv_deg": cv, "delta_bic": float(delta_bic), "params": params,
            "plausible": plausible, "significant": significant,
            "delta_bic_vs_null": float(delta_bic_null),
            "z": {k: _num(v) for k, v in z.items()},
            "explained_fraction": float(explained), "selectable": ok,
            "why_not": reasons})
    for eid in EFFECT_IDS:
        if eid not in singles:
            st = status[eid]
            candidates.append({"effect": eid, "effects": [eid], "kind": EFFECTS[eid].kind,
                               "applicable": st["applicable"], "identifiable":
                               st["identifiable"], "confounded_with": st["confounded_with"],
                               "rmse_cv_deg": None, "delta_bic": None, "params": {},
                               "plausible": None, "significant": None, "selectable": False,
                               "why_not": [st["note"]]})

    chosen: tuple[str, ...] = min(selectable)[1] if selectable else ()
    after = get_fit(chosen)
    rmse_after, resid_after = get_cv(chosen)
    structure = structure_test(obs.curve, after.residual, _nuisance(obs, after))
    confounded = [{"effects": [eid, status[eid]["confounded_with"]],
                   "reason": status[eid]["note"]} for eid in EFFECT_IDS
                  if status[eid]["confounded_with"]]
    confounded.append({"effects": ["stiffness_scale", "recalibrated a_t"],
                       "reason": "all moduli x s is the actuator at p/s: tau -> s tau, "
                       "exactly a change of a_t; stiffness_scale is therefore fitted with "
                       "a_t, b_t pinned at the starting model (as is "
                       "membrane_thickness_bias, nearly a change of b_t)"})
    report = {
        "schema": REPORT_SCHEMA,
        "model": model or {"name": "paper"},
        "data": {"sha256": obs.sha256, "n_rows": obs.n, "n_curves": obs.n_curves,
                 "families": [dict(zip(("body_material", "membrane_material", "T_mm", "b_mm",
                                        "h_mm"), f, strict=False)) for f in obs.families],
                 "has_time_s": obs.has_time, "has_flow_ul_s": obs.has_flow,
                 "flow_rates_ul_s": [float(q) for q in flows],
                 "angle_sd_median_deg": _num(float(np.nanmedian(obs.angle_sd_deg)))
                 if np.any(np.isfinite(obs.angle_sd_deg)) else None},
        "rmse_model_deg": rmse_model,
        "rmse_before_deg": rmse_before,
        "rmse_after_deg": rmse_after,
        "noise_floor_deg": _num(noise.rms_deg),
        "noise_floor_source": noise.source,
        "cross_validation": {"method": "grouped K-fold by curve", "folds": folds,
                             "folds_requested": folds_requested},
        "selected_effects": list(chosen),
        "candidates": candidates,
        "confounded": confounded,
        "baseline_before": _family_table(obs, base),
        "fitted": {"families": _family_table(obs, after), "effects": _physical_params(after)},
        "residual_structured_after": bool(structure["structured"]),
        "structure_after": structure,
        "selection_rule": {"z_significant": Z_SIGNIFICANT, "delta_bic_below": DELTA_BIC,
                           "explained_fraction_min": EXPLAINED_FRACTION,
                           "parameter_cv_tolerance": PARAMETER_CV_TOLERANCE},
    }
    report["interpretation"] = interpret(report, obs, status)
    return Calibration(report, obs, nominal, base, after, resid_before, resid_after)


def _family_table(obs: Observations, f: FitResult) -> list[dict]:
    out = []
    for i, fam in enumerate(obs.families):
        a, a_t, b_t, c = (float(v) for v in f.families[i])
        out.append({"body_material": fam[0], "membrane_material": fam[1], "T_mm": fam[2],
                    "b_mm": fam[3], "h_mm": fam[4], "a_deg_per_mm": a, "a_t_pa": a_t,
                    "b_t_per_mm": b_t, "c": c,
                    "tau_form": "tau_pa = a_t_pa * log10(b_t_per_mm * t_mm)",
                    "tau_law_pinned": f.pinned})
    return out


def interpret(report: dict, obs: Observations, status: dict) -> str:
    """A few sentences a lab can act on."""
    noise = report["noise_floor_deg"]
    floor = (f"against a noise floor of {noise:.2f} deg from {report['noise_floor_source']}"
             if noise is not None else "with no noise floor to compare against (it needs "
             f"replicate curves of one design, or more than {N_FLEX + 1} points per curve)")
    s = [f"The model as is misses the data by {report['rmse_model_deg']:.2f} deg RMS; "
         f"with its own constants refitted it predicts unseen curves to "
         f"{report['rmse_before_deg']:.2f} deg (cross-validated by curve), {floor}."]
    fitted = report["fitted"]["effects"]
    flows = report["data"]["flow_rates_ul_s"]
    q = flows[0] if len(flows) == 1 else (max(flows) if flows else None)
    for eid in report["selected_effects"]:
        p = {k: v for k, v in fitted.items() if v["effect"] == eid}
        if eid == "pressure_offset":
            v = p["p0_pa"]
            line = (f"The gauge reads {v['value']:.0f} +/- {v['sd']:.0f} Pa above the chamber "
                    "(gauge zero or transition pressure)")
            if status["hydraulic_resistance"]["confounded_with"] and q:
                line += (f"; at the single flow rate of {q:g} ul/s this is equally an inlet "
                         f"resistance of {v['value'] / q:.0f} Pa per ul/s (the channel alone "
                         f"gives about {R_CHANNEL:.0f}): measure at a second flow rate to "
                         "tell them apart")
            s.append(line + ".")
        elif eid == "hydraulic_resistance":
            v = p["R_pa_per_ul_s"]
            s.append(f"Inlet channel and tubing resistance {v['value']:.0f} +/- {v['sd']:.0f} "
                     f"Pa per ul/s: the gauge reads about {v['value'] * (q or 2.5):.0f} Pa "
                     f"above the chamber at {q or 2.5:g} ul/s (the 0.5 mm x 3 mm x 150 um "
                     f"channel alone accounts for about {R_CHANNEL:.0f} Pa per ul/s; the rest "
                     "is tubing and connectors). Measure pressure at the chip or correct it.")
        elif eid == "angle_offset":
            v = p["offset_deg"]
            s.append(f"The actuator rests at {v['value']:.1f} +/- {v['sd']:.1f} deg at zero "
                     "pressure (pre-curvature or sag): zero the angle on the unpressurised "
                     "actuator.")
        elif eid == "saturation":
            v = p["theta_max_deg"]
            s.append(f"The bend saturates towards {v['value']:.0f} deg "
                     f"(+/- {v['sd']:.0f}): the exponential model overpredicts large angles; "
                     "check for contact between balloon and body.")
        elif eid == "reverse_bending":
            v, w = p["depth_deg"], p["p_r_pa"]
            s.append(f"Below the transition it first bends towards the balloon, by up to "
                     f"{v['value']:.1f} +/- {v['sd']:.1f} deg near {w['value']:.0f} Pa, which "
                     "the paper's model neglects.")
        elif eid == "viscoelastic_lag":
            v = p["tau_v_s"]
            s.append(f"The angle lags its static value with a time constant of "
                     f"{v['value']:.2f} +/- {v['sd']:.2f} s (silicone creep): readings taken "
                     "while pumping understate the static angle; hold the pressure for about "
                     f"{3 * v['value']:.1f} s or pump more slowly.")
        elif eid == "stiffness_scale":
            v = p["s"]
            s.append(f"The silicones behave {100 * (v['value'] - 1):+.0f} % "
                     f"(+/- {100 * v['sd']:.0f} %) stiff relative to the nominal parameters "
                     "(every tau scaled alike): check mixing ratio and cure.")
            if status["membrane_thickness_bias"]["confounded_with"]:
                s.append("With a single membrane thickness this is indistinguishable from a "
                         "membrane thickness bias; test a second thickness to separate them.")
        elif eid == "membrane_thickness_bias":
            v = p["dt_mm"]
            s.append(f"The membranes behave {1000 * v['value']:+.0f} +/- "
                     f"{1000 * v['sd']:.0f} um thicker than nominal (thin membranes affected "
                     "most): measure the spin-coated thickness.")
    if not report["selected_effects"]:
        s.append("No catalogued effect is warranted: none improves the cross-validated error "
                 "by more than the replicate scatter explains with physically plausible "
                 "values.")
    else:
        s.append(f"With {' and '.join(report['selected_effects'])} the cross-validated error "
                 f"is {report['rmse_after_deg']:.2f} deg.")
    st = report["structure_after"]
    if report["residual_structured_after"]:
        r1 = st["lag1_autocorrelation"]
        s.append(f"What remains is NOT noise (lag-1 autocorrelation {r1:.2f}, "
                 f"z = {st['z_lag1']:.1f}; runs z = {st['z_runs']:.1f}): an effect outside "
                 "the catalogue acts on these data, so this calibration does not explain them; "
                 "look at the residual plot before trusting the augmented model.")
    else:
        s.append("What remains is consistent with replicate noise (no structure along the "
                 "curves).")
    return " ".join(s)
