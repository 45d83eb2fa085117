"""The loop: model as is -> recalibrated baseline -> candidate effects -> selection ->
what is left. ``calibrate(obs, baseline)`` returns a ``Calibration`` whose ``report`` is
the JSON report (docs/calibration.md describes every field).

Its parts, each a module: which readings the baseline can be compared with
(_reading_checks.py), the pump's switch times (_pump_switches.py), the rule that judges
each candidate set of effects and chooses one (_selection.py), the gauge pressure left
after it (_gauge_check.py), the report's tables (_report_tables.py) and the sentences a
lab reads (_interpretation.py). This module runs them in order and writes the report.
"""

from __future__ import annotations

import itertools
import math
import threading
from dataclasses import dataclass, field, replace

import numpy as np

from solver.errors import InputError
from surrogate.calibration._augmented_model import AugmentedModel
from surrogate.calibration._backing import with_baseline_uncertainty
from surrogate.calibration._data import Observations
from surrogate.calibration._errors import DataError
from surrogate.calibration._exact_alike import exact_alikes
from surrogate.calibration._first_run import first_run_against_later
from surrogate.calibration._gauge_check import gauge_left, gauge_worse, pressure_rms_pa, reads_gauge
from surrogate.calibration._gauge_zero import (
    gauge_at_rest,
    wants_zeroed_pass,
    whole_curve_offsets,
    zeroed_summary,
)
from surrogate.calibration._held_reading import held_instead, reads_better, wants_held_reading
from surrogate.calibration._held_reading import summary as held_summary
from surrogate.calibration._history import history_traits
from surrogate.calibration._interpretation import interpret
from surrogate.calibration._least_squares import (
    R_CAP_DEG,
    CrossValidation,
    FitResult,
    cross_validate,
    fit,
    paired_cv,
)
from surrogate.calibration._measured_volume import is_absent
from surrogate.calibration._noise import NoiseFloor, noise_floor, volume_floor
from surrogate.calibration._pump_switches import pump_switches_open, switch_table
from surrogate.calibration._reading_checks import (
    MIN_CURVES,
    radians_warning,
    sign_warning,
    table_end_pa,
    usable_rows,
    within_volume_range,
)
from surrogate.calibration._report_tables import (
    family_constants,
    finite_or_none,
    left_out_check,
    open_table,
    prediction_rows,
)
from surrogate.calibration._residual import residual_summary, scatter_shift
from surrogate.calibration._response import Responses, design_key
from surrogate.calibration._selection import (
    DELTA_BIC,
    Z_SIGNIFICANT,
    better_unbacked,
    better_within_scatter,
    closest_rejected,
    effect_status,
    explains_better,
    explains_better_words,
    indistinguishable,
    judge,
    parameter_table,
    wants_specimens_beyond,
)
from surrogate.calibration._specimens import SpecimenScatter, specimen_scatter
from surrogate.calibration._start import Baseline
from surrogate.calibration._structure import structure_test
from surrogate.calibration.effects import CATALOGUE, EFFECTS, DataTraits
from surrogate.errors import stop_if_cancelled

PAIRS_CROSS_VALIDATED = 4
REPORT_SCHEMA = "balloon.calibration.report/2"


@dataclass
class Calibration:
    """The result of the loop: the JSON ``report`` plus the fits (for plots and saving)."""

    report: dict
    obs: Observations
    baseline: Baseline
    before: FitResult
    after: FitResult
    residual_before_cv: np.ndarray = field(repr=False)
    residual_after_cv: np.ndarray = field(repr=False)


def folds_used(folds: object, n_curves: int) -> int:
    if isinstance(folds, bool) or not isinstance(folds, int | np.integer) or folds < 2:
        raise InputError("folds", f"not an integer >= 2: {folds!r}",
                         "integer folds >= 2 (reduced to the number of curves)")
    return min(int(folds), n_curves)


def data_traits(obs: Observations, open_parameters: tuple[str, ...],
                by_volume: bool = False) -> DataTraits:
    h = history_traits(obs.curve, obs.pressure_pa, obs.direction)
    flows = np.unique(np.round(obs.flow_ul_s[np.isfinite(obs.flow_ul_s)], 6))
    t_max = max(np.unique(obs.t_mm[obs.family == f]).size for f in set(obs.family.tolist()))
    l_max = max(np.unique(obs.L_mm[obs.family == f]).size for f in set(obs.family.tolist()))
    return DataTraits(obs.has_time, obs.has_flow, int(flows.size), h["unloading"] > 0,
                      h["hold"] > 0 and obs.has_time, t_max, l_max, open_parameters,
                      by_volume)


def calibrate(obs: Observations, baseline: Baseline, folds: int = 5, progress=None,
              cancel: threading.Event | None = None, zeroed: bool = False,
              unloading_read: dict | None = None) -> Calibration:
    """Run the loop on validated observations against ``baseline``. ``cancel``: checked
    before the baseline is tabulated and at every fit and cross-validation (where
    ``progress`` ticks); once set, the loop ends with ``Cancelled``. ``zeroed``: the
    gauge's readings already have their zero at rest taken off (no second pass).
    ``unloading_read``: this is the pass with the falling readings read as a hold, and
    that was the first reading's summary (_held_reading.py)."""
    stop_if_cancelled(cancel)
    # every reading as given: a second reading of the pump's history (_held_reading) is
    # made from all of them, the ones a stopped sensor pinned included -- their time
    # between the readings kept is the pump's too (read from the kept rows alone, a stop
    # at the top of a loading put its injection into the first unloading reading after)
    given = obs
    if obs.angle_stop is not None and obs.angle_stop.pinned.any():   # (warned at loading)
        obs = obs.rows(~obs.angle_stop.pinned)
    if obs.n_curves < MIN_CURVES:
        ids = ", ".join(repr(c) for c in obs.curve_ids)
        raise DataError("curve_id", f"{obs.n_curves} curve ({ids}): cross-validation by "
                        "curve needs a second curve to predict", None,
                        f"at least {MIN_CURVES} curves (distinct curve_id); replicate "
                        "specimens of one design also give the noise floor")
    if obs.n_specimens < MIN_CURVES:     # one actuator loaded again: its runs compared
        obs = obs.as_replicates()
    folds_requested = folds
    k = folds_used(folds, obs.n_specimens)
    def tick() -> None:
        stop_if_cancelled(cancel)
        if progress is not None:
            progress()

    warnings = list(obs.warnings)

    designs = {}
    for c in range(obs.n_curves):
        d = obs.design(c)
        designs.setdefault(design_key(d), d)
    p_max = table_end_pa(baseline.predictor, designs,
                         1.6 * float(np.max(np.abs(obs.pressure_pa))) + 200.0)
    v_max = 1.25 * float(np.max(obs.volume_ul)) + 1.0 if obs.has_volume else None
    responses = Responses(baseline.predictor, designs, p_max, v_max)
    stop_if_cancelled(cancel)
    channel, noise = pressure_channel(obs, responses, baseline)
    # by volume a reading is past the baseline's range by its volume, not by its gauge
    # pressure (which a specimen's scatter or a gauge effect moves: no selection by it)
    all_obs = obs
    obs, kept = usable_rows(obs, responses, baseline, warnings, by_gauge=not channel["used"])
    if channel["used"]:
        obs, kept_v = within_volume_range(obs, responses, warnings)
        kept[np.flatnonzero(kept)] = kept_v

    traits = data_traits(obs, baseline.open_parameters, channel["used"])
    fits: dict[tuple[str, ...], FitResult] = {}
    cvs: dict[tuple[str, ...], CrossValidation] = {}
    switches, without = pump_switches_open(obs, responses, baseline, channel, k)
    if without is not None and not switches["open"]:   # the recalibrated baseline, done
        fits[()], cvs[()] = without

    scatter = _specimen_scatter(obs, responses, baseline, channel)

    def make(effects: tuple[str, ...]):
        chosen = tuple(EFFECTS[e] for e in effects)
        return lambda o: AugmentedModel(o, responses, chosen, baseline.open_parameters,
                                        channel["weight_deg_per_pa"], switches["open"],
                                        scatter)

    def get_fit(effects: tuple[str, ...]) -> FitResult:
        if effects not in fits:
            fits[effects] = with_baseline_uncertainty(fit(make(effects)(obs)), responses)
            tick()
        return fits[effects]

    def get_xv(effects: tuple[str, ...]) -> CrossValidation:
        if effects not in cvs:
            cvs[effects] = cross_validate(obs, make(effects), get_fit(effects), k)
            tick()
        return cvs[effects]

    def get_cv(effects: tuple[str, ...]) -> tuple[float, np.ndarray]:
        """Cross-validated angle error (deg) and the out-of-fold angle residuals."""
        xv = get_xv(effects)
        return xv.rmse_deg, xv.angle

    y = obs.angle_deg
    as_is = AugmentedModel(obs, responses, (), baseline.open_parameters)
    pred_as_is = as_is.angles(as_is.layout.start)
    # by volume a gauge reading past the baseline's range has no angle at that pressure
    rmse_model = float(np.sqrt(np.nanmean((pred_as_is - y) ** 2)))
    for check in (radians_warning, sign_warning):
        said = check(y, pred_as_is)
        if said:
            warnings.append(said)
    base = get_fit(())
    rmse_before, resid_before = get_cv(())

    status = {e.id: effect_status(e, traits, responses) for e in CATALOGUE}
    singles = [e.id for e in CATALOGUE if status[e.id]["reason"] is None]
    for eid in singles:
        get_fit((eid,))
    promising = {e for e in singles if get_fit((e,)).bic < base.bic + DELTA_BIC}
    pairs = [p for p in itertools.combinations(singles, 2) if promising & set(p)
             and not (EFFECTS[p[0]].stage == EFFECTS[p[1]].stage == "time")]
    for p in pairs:
        get_fit(p)
    pairs.sort(key=lambda p: get_fit(p).bic)
    evaluated = [(e,) for e in singles] + pairs[:PAIRS_CROSS_VALIDATED]

    by_volume = AugmentedModel(obs, responses, (), baseline.open_parameters,
                               channel["weight_deg_per_pa"])
    sd_rows = responses.lookup(responses.nominal_sd(), as_is.design_index,
                               by_volume.reading_pressure(np.zeros(0)))
    baseline_var = float(np.nanmean(sd_rows**2)) if np.any(np.isfinite(sd_rows)) else 0.0

    def own_var(effects: tuple[str, ...], backed: bool = True) -> float:
        """The baseline's own variance where the set puts the designs: at the fitted
        physical change (its band there) when the size is backed against it, else at
        the nominal designs (a band too wide to back a size must not excuse a misfit)."""
        sd = get_fit(effects).baseline_sd_deg
        return baseline_var if sd is None or not backed else max(sd**2, baseline_var)

    def shift(effects: tuple[str, ...]) -> np.ndarray | None:
        """The specimens' mean angle above the nominal at each gauge reading
        (_residual.scatter_shift) at the set's fit; None by injected volume."""
        if scatter is None:
            return None
        f = get_fit(effects)
        return scatter_shift(lambda s: f.model.angles(f.x, pscale=s), scatter.tau)

    def along(effects: tuple[str, ...]) -> dict:
        """The set's residuals along the curves, beyond each specimen's own amplitude and
        pressure scale (_structure.py)."""
        f = get_fit(effects)
        return structure_test(obs.curve, f.residual, _nuisance(f))

    def leaves(effects: tuple[str, ...], backed: bool = True) -> dict:
        cv, resid = get_cv(effects)
        quiet = {"structured": False, "z_lag1": 0.0, "z_runs": 0.0}
        return residual_summary(obs, resid, cv, noise,
                                along(effects) if scatter is not None else quiet,
                                own_var(effects, backed), shift(effects),
                                by_gauge=scatter is not None)

    candidates, selectable = [], []
    base_joint = get_xv(()).rmse_joint
    base_gauge_pa = pressure_rms_pa(get_xv(()), channel)
    for effects in evaluated:
        cand = judge(effects, get_fit, get_xv, base, rmse_before, base_joint, responses,
                     channel["weight_deg_per_pa"])
        cand["excused"] = False
        if cand["selectable"] or not cand["why_not"] or cand["unbacked"]:
            rest = leaves(effects, backed=not cand["unbacked"])
            cand["unexplained_rms_deg"] = rest["unexplained_rms_deg"]
            gauge_pa = pressure_rms_pa(get_xv(effects), channel)
            worse = gauge_worse(gauge_pa, base_gauge_pa)
            gauge = (gauge_left(gauge_pa, channel, rest["plain_allowance"])
                     if reads_gauge(effects) or worse else None)
            if rest["structured"]:
                cand["selectable"] = cand["unbacked"] = False
                cand["why_not"].append(
                    f"leaves a shared residual of {rest['unexplained_rms_deg']:.2f} deg: it "
                    "does not explain the data (something outside the catalogue acts)")
            elif gauge and gauge["left"]:
                cand["selectable"] = cand["unbacked"] = False
                cand["why_not"].append(
                    f"leaves the gauge at {gauge['rmse_pa']:.0f} Pa against its floor of "
                    f"{gauge['floor_pa']:.0f} Pa ({gauge['ratio']:.2f} x, more than "
                    f"{gauge['limit']:.2f} x): " + (
                        "an effect read off the gauge that does not explain the gauge is "
                        "not its explanation" if reads_gauge(effects) else
                        f"worse than the baseline's {base_gauge_pa:.0f} Pa, it moves the "
                        "gauge where the data do not"))
            elif not cand["unbacked"] and get_fit(effects).baseline_sd_deg is not None:
                # what it leaves is within the baseline's band at the fitted design, but
                # would not be within its band at the nominal designs
                cand["excused"] = bool(leaves(effects, backed=False)["structured"])
        candidates.append(cand)
        if cand["selectable"]:
            selectable.append((cand["bic"], effects))
    for e in CATALOGUE:
        st = status[e.id]
        if st["reason"] is not None:
            candidates.append({"effect": e.id, "effects": [e.id], "kind": e.kind,
                               "applicable": st["applicable"], "identifiable": False,
                               "rmse_cv_deg": None, "delta_bic": None, "params": {},
                               "plausible": None, "significant": None, "selectable": False,
                               "why_not": [st["reason"]], "measure": st["measure"]})

    chosen: tuple[str, ...] = ()
    for _, effects in sorted(selectable):
        cand = next(c for c in candidates if tuple(c["effects"]) == effects)
        better = explains_better(cand, candidates) if cand["excused"] else None
        # (a set that holds this one and adds an unbacked member does not replace it)
        rival = better_unbacked([c for c in candidates
                                 if not set(effects) < set(c["effects"])], effects, base_joint)
        unsized = better_within_scatter(candidates, effects) if rival is None else None
        if better is None and rival is None and unsized is None:
            chosen = effects
            break
        cand["selectable"] = False
        if better is None and unsized is not None:   # the data prefer a set they cannot size
            z = ", ".join(f"z {v:.1f}" for v in unsized["z"].values())
            cand["why_not"].append(
                explains_better_words(unsized, cand, channel["used"]) + " but its size is "
                f"within what replicate scatter explains ({z}): this set would stand in for "
                "an explanation the data cannot size")
            cand["stands_in_for"] = unsized["effects"]
            cand["stands_in_because"] = "replicate scatter"
            continue
        if better is None:      # the data prefer a set the baseline cannot back
            cand["why_not"].append(
                explains_better_words(rival, cand, channel["used"]) + " but the baseline "
                "cannot back its size there: this set would stand in for it")
            cand["stands_in_for"] = rival["effects"]
            cand["stands_in_because"] = "the baseline's backing"
            continue
        cand["why_not"].append(
            "what it leaves is within the baseline's own uncertainty at the fitted design "
            "only, while " + explains_better_words(better, cand, channel["used"],
                                                   " (plausible)")
            + ": the baseline's uncertainty does not excuse the worse fit")
        cand["outdone_by"] = better["effects"]
    xv_chosen = get_xv(chosen)
    for cand in candidates:
        if cand["rmse_cv_deg"] is not None:  # both channels, paired by curve
            cand["paired_z"] = finite_or_none(paired_cv(
                get_xv(tuple(cand["effects"])).joint, xv_chosen.joint,
                xv_chosen.curves(obs.specimen)))
    alike = indistinguishable(candidates, chosen)
    if chosen:
        ref = next(c for c in candidates if tuple(c["effects"]) == chosen)
        for a in exact_alikes(chosen, parameter_table(get_fit(chosen)), ref["rmse_cv_deg"],
                              ref["rmse_cv_pressure_pa"]):
            same = [b for b in alike if set(b["effects"]) == set(a["effects"])]
            if same:  # fitted as a candidate too: its own sizes, said to be exact
                same[0].update(exact=True, why=a["why"], measure=a["measure"])
            else:
                alike.insert(0, a)
    # a set the data prefer that fails only for want of the baseline's backing: reported
    # beside the selection (its CV advantage may be the baseline's own error there)
    unbacked = better_unbacked(candidates, chosen, base_joint)
    after = get_fit(chosen)
    rmse_after, resid_after = get_cv(chosen)
    rest = (gauge_at_rest(obs.curve, obs.volume_ul, obs.pressure_pa,
                          after.model.gauge_pressures(after.x))
            if channel["used"] and "hydraulic_resistance" not in chosen else None)
    runs = (first_run_against_later(obs.curve, obs.specimen, obs.volume_ul, obs.direction,
                                    obs.pressure_pa) if channel["used"] else None)
    nuisance = _nuisance(after)
    structure = structure_test(obs.curve, after.residual, nuisance)
    left = residual_summary(obs, resid_after, rmse_after, noise, structure,
                            own_var(chosen), shift(chosen),
                            by_gauge=scatter is not None)
    gauge_after = gauge_left(pressure_rms_pa(get_xv(chosen), channel), channel,
                             left["plain_allowance"])
    if rest is not None and rest["off"]:
        rest = {**rest, "whole_curves": whole_curve_offsets(candidates)}
    if not zeroed and wants_zeroed_pass(rest, chosen, gauge_after):
        again = calibrate(replace(all_obs, pressure_pa=all_obs.pressure_pa - rest["mean_pa"]),
                          baseline, folds, progress, cancel, zeroed=True)
        rest = {**rest, "zeroed": zeroed_summary(again.report)}
    not_identifiable = [{"effect": e.id, "reason": status[e.id]["reason"],
                         "measure": status[e.id]["measure"]}
                        for e in CATALOGUE if status[e.id]["reason"] is not None]
    h = history_traits(obs.curve, obs.pressure_pa, obs.direction)
    report = {
        "schema": REPORT_SCHEMA,
        "model": {"name": baseline.name},
        "baseline": baseline.as_dict(),
        "data": {"sha256": obs.sha256, "n_rows": obs.n, "n_curves": obs.n_curves,
                 "n_specimens": 1 if obs.runs_as_replicates else obs.n_specimens,
                 "runs_as_replicates": obs.runs_as_replicates,
                 "families": [dict(zip(("body_material", "membrane_material", "T_mm", "b_mm",
                                        "h_mm"), f, strict=False)) for f in obs.families],
                 "has_time_s": obs.has_time, "has_flow_ul_s": obs.has_flow,
                 "pump_logged": obs.pump_logged,
                 "has_volume_ul": not is_absent(obs.measured_volume_ul),
                 "injected_volume": obs.volume_source,
                 "volume_ul_used_for": [obs.curve_ids[c] for c in np.unique(
                     obs.curve[obs.volume_measured])],
                 "columns_read": [r.as_dict() for r in obs.columns_read],
                 "clock_columns": [dict(c) for c in obs.clock_columns],
                 "columns_not_read": [dict(c) for c in obs.columns_not_read],
                 "flow_rates_ul_s": sorted({float(q) for q in np.round(
                     obs.flow_ul_s[np.isfinite(obs.flow_ul_s)], 6)}),
                 "readings": h, "holds": traits.has_holds, "unloading": traits.has_unloading,
                 "angle_sd_median_deg": finite_or_none(float(np.nanmedian(obs.angle_sd_deg)))
                 if np.any(np.isfinite(obs.angle_sd_deg)) else None},
        "warnings": warnings,
        "rmse_model_deg": rmse_model,
        "rmse_before_deg": rmse_before,
        "rmse_after_deg": rmse_after,
        "noise_floor_deg": finite_or_none(noise.rms_deg),
        "noise_floor_source": noise.source,
        "noise_floor_basis": channel["angle_floor_basis"],
        "specimen_scatter": None if scatter is None else scatter.as_dict(),
        "pressure_channel": channel,
        "rmse_pressure_before_pa": pressure_rms_pa(get_xv(()), channel),
        "rmse_pressure_after_pa": pressure_rms_pa(get_xv(chosen), channel),
        "gauge_at_rest": rest,
        "first_run_against_later": runs,
        "angle_stop": None if obs.angle_stop is None else obs.angle_stop.as_dict(),
        "gauge_left_after": gauge_after,
        "cross_validation": {"method": _cv_method(obs), "folds": k,
                             "folds_requested": folds_requested},
        "selected_effects": list(chosen),
        "candidates": candidates,
        "not_identifiable": not_identifiable,
        "confounded": [{"effects": [c["effect"]], "reason": c["reason"]}
                       for c in not_identifiable if "exactly" in c["reason"]],
        "pump_switches": {**switches, "shifts": switch_table(after)},
        "fitted": {"open": open_table(obs, base, after), "effects": parameter_table(after),
                   **family_constants(obs, baseline, base, after)},
        "residual_structured_after": left["structured"],
        "residual_within_baseline_band": left["within_baseline_band"],
        "unexplained_rms_deg": left["unexplained_rms_deg"],
        "unexplained_where": left["where"],
        "systematic_residual": left["systematic"],
        "baseline_sd_deg": math.sqrt(baseline_var),
        "baseline_sd_after_deg": math.sqrt(own_var(chosen)),
        "noise_floor_rel_se": finite_or_none(noise.rel_se),
        "excess_allowance": left["excess_allowance"],
        "structure_after": structure,
        "selection_rule": {"z_significant": Z_SIGNIFICANT, "delta_bic_below": DELTA_BIC,
                           "cv_below": "rmse_before_deg", "pairs": "each member earns its "
                           "place (BIC - 6 and lower CV than each alone)"},
        "unbacked_better": unbacked,
        "indistinguishable": alike,
        "closest_rejected": (closest_rejected(candidates, rmse_before)
                             if not chosen and left["structured"] else None),
        "wants_specimens_beyond": wants_specimens_beyond(candidates, chosen),
        "baseline_calls": responses.calls,
        "baseline_reach": {e.id: responses.reach(e).as_dict() for e in CATALOGUE
                           if e.stage == "design" and responses.reach(e).limits},
    }
    report["left_out"], left_rows = left_out_check(all_obs, kept, make(chosen), after)
    report["predictions"] = prediction_rows(obs, base, after) + left_rows
    report["history_read_as_hold"] = None
    if unloading_read is not None:
        report["history_read_as_hold"] = {"taken": True, "unloading": unloading_read,
                                          "hold": held_summary(report)}
    elif not zeroed and wants_held_reading(report):
        first = held_summary(report)
        held = calibrate(held_instead(given), baseline, folds, progress, cancel,
                         unloading_read=first)
        if reads_better(held.report["history_read_as_hold"]["hold"], first):
            return held
        report["history_read_as_hold"] = {**held.report["history_read_as_hold"],
                                          "taken": False}
    report["interpretation"] = interpret(report, left)
    return Calibration(report, obs, baseline, base, after, resid_before, resid_after)


def pressure_channel(obs: Observations, responses: Responses, baseline: Baseline
                     ) -> tuple[dict, NoiseFloor]:
    """Whether the data are read as a syringe pump's two observables (docs/calibration.md,
    "Two observables"): angle and gauge pressure at each reading's injected volume; with
    the angle's noise floor in the same terms. The weight of the gauge residual is the
    angle's floor over the pressure's (deg per Pa), so each counts by its own replicate
    scatter. Otherwise (``used`` false, ``why_not``): the angle at the gauge pressure, its
    floor at the same pressure."""
    why = None
    floor_a = volume_floor(obs, obs.angle_deg) if obs.has_volume else None
    floor_p = volume_floor(obs, obs.pressure_pa) if obs.has_volume else None
    if not obs.has_volume:
        why = ("needs time_s and flow_ul_s, or volume_ul, on every reading (the injected "
               "volume)")
    elif baseline.open_parameters:
        why = ("the baseline leaves its pressure scale open per family, so its pressure at "
               "a volume is open too")
    elif not responses.has_volumes():
        why = "the baseline gives no injected volume with its answer"
    elif floor_a is None or floor_p is None:
        why = "needs replicate curves for the pressure's and the angle's noise floors"
    if why is not None:
        return ({"used": False, "why_not": why, "pressure_floor_pa": None,
                 "weight_deg_per_pa": 0.0, "angle_floor_basis": "gauge pressure"},
                noise_floor(obs))
    return ({"used": True, "why_not": None, "pressure_floor_pa": floor_p.rms_deg,
             "weight_deg_per_pa": floor_a.rms_deg / floor_p.rms_deg,
             "angle_floor_basis": "injected volume"}, floor_a)


def _cv_method(obs: Observations) -> str:
    """How the cross-validation holds curves out, as the report says it."""
    if obs.runs_as_replicates:
        return "grouped K-fold by run (the runs of one specimen taken as replicates)"
    if obs.n_specimens == obs.n_curves:
        return "grouped K-fold by curve"
    return "grouped K-fold by specimen (its runs held out together)"


def _nuisance(f: FitResult) -> np.ndarray:
    """d angle / d log amplitude and d angle / d log pressure scale at every row: what a
    specimen-to-specimen change explains (per curve, in the structure test)."""
    h = 1e-3
    base = f.model.angles(f.x)
    return np.column_stack([(f.model.angles(f.x, amp=1 + h) - base) / h,
                            (f.model.angles(f.x, pscale=1 + h) - base) / h])


def _specimen_scatter(obs: Observations, responses: Responses, baseline: Baseline,
                      channel: dict) -> SpecimenScatter | None:
    """The specimens' pressure-scale scatter, from the recalibrated baseline's residuals
    (_specimens.py), where the angle is read against the gauge pressure; None by injected
    volume (the specimens' stiffness does not move the angle there)."""
    if channel["used"]:
        return None
    m = AugmentedModel(obs, responses, (), baseline.open_parameters)
    f = fit(m)
    r = np.where(np.abs(f.residual) < R_CAP_DEG, f.residual, np.nan)  # capped: no answer
    return specimen_scatter(r, m.pressure_scale_direction(f.x), obs.replicate_unit(),
                            obs.group)
















