"""The report's interpretation: a few sentences a lab can act on, written from the
finished report (what the baseline misses, what was selected and at what size, what the
data cannot tell apart and how to measure it, what is left and what would decide)."""

from __future__ import annotations

import math

from surrogate.calibration._backing import PRESSURE_SCALE_SD
from surrogate.calibration._exact_alike import sentence as exact_alike_sentence
from surrogate.calibration._first_run import first_run_sentence
from surrogate.calibration._gauge_check import gauge_gain_clause, gauge_sentence
from surrogate.calibration._gauge_zero import sentence as gauge_zero_sentence
from surrogate.calibration._held_reading import sentence as held_sentence
from surrogate.calibration._pump_switches import pump_sentence
from surrogate.calibration.effects import EFFECTS


def interpret(report: dict, left: dict) -> str:
    """A few sentences a lab can act on."""
    noise = report["noise_floor_deg"]
    basis = (" at the same injected volume (angle and gauge pressure read against the "
             "pump's volume)" if report["pressure_channel"]["used"] else "")
    floor = (f"against a noise floor of {noise:.2f} deg from {report['noise_floor_source']}"
             f"{basis}"
             if noise is not None else "with no noise floor to compare against (it needs "
             "replicate curves of one design)")
    b = report["baseline"]
    opened = (f"with its {' and '.join(b['open_parameters'])} per family refitted"
              if b["open_parameters"] else "with nothing refitted (a design-space model "
              "leaves nothing open)")
    by_volume = report["pressure_channel"]["used"]
    before = report["rmse_before_deg"]
    if before is None or not math.isfinite(before):
        # held-out curves past the end of the refitted baseline's range: no error at all
        return (f"The baseline {b['name']!r} as is misses the data by "
                f"{report['rmse_model_deg']:.2f} deg RMS; {opened} it gives no angle at "
                "some readings of held-out curves (past the end of its range for those "
                "designs: its FE curves stop below the measured pressures), so the "
                "cross-validation by curve has no error to report and nothing can be "
                "selected or saved. Calibrate against the emulator (the default, whose "
                "range is each design's own), or leave out the readings past the model's "
                "range.")
    unit = ("run" if report["data"]["runs_as_replicates"] else
            "specimen" if "specimen" in report["cross_validation"]["method"] else "curve")
    s = [f"The baseline {b['name']!r} as is misses the data by "
         f"{report['rmse_model_deg']:.2f} deg RMS"
         + (" (the angle read at the gauge's pressure)" if by_volume else "")
         + f"; {opened} it predicts unseen {unit}s to "
         f"{before:.2f} deg (cross-validated by {unit}"
         + (", the angle read at the injected volume" if by_volume else "")
         + f"), {floor}."]
    if report["pump_switches"]["open"]:
        leaking = [e for e in report["selected_effects"] if EFFECTS[e].lags == "volume"
                   and EFFECTS[e].stage == "time"]
        s.append(pump_sentence(report["pump_switches"], leaking))
    fitted = report["fitted"]["effects"]
    for eid in report["selected_effects"]:
        p = {k: v for k, v in fitted.items() if v["effect"] == eid}
        s.append(EFFECTS[eid].interpret(p, report["data"]))
    if report["selected_effects"]:
        s.append(f"With {' and '.join(report['selected_effects'])} the cross-validated error "
                 f"is {report['rmse_after_deg']:.2f} deg" + gauge_gain_clause(report) + ".")
    else:
        s.append("No catalogued effect is warranted: none lowers the cross-validated error "
                 "and the BIC with physically plausible, significant values and leaves "
                 "only replicate scatter.")
    exact = exact_alike_sentence(report["selected_effects"],
                                 report.get("indistinguishable") or [])
    if exact:
        s.append(exact)
    alike = [a for a in report.get("indistinguishable") or [] if not a.get("exact")]
    if alike:
        sets = "; ".join(
            " and ".join(a["effects"]) + " (" + _sizes(a["params"]) + ", cross-validated "
            f"{a['rmse_cv_deg']:.2f} deg" + ("" if a["backed"] else ", not backed by the "
                                             "baseline") + ")" for a in alike)
        chosen = " and ".join(report["selected_effects"])
        measures = [m for e in report["selected_effects"]
                    for m in [EFFECTS[e].measure_directly]]
        measures += [m for a in alike for m in a["measure"] if m not in measures]
        s.append(f"These data do not tell {chosen} from {sets}: each predicts unseen curves "
                 "as well (paired by curve, |z| < 2), so the choice of "
                 f"{chosen} is the lowest BIC, not evidence. To tell them apart: "
                 + "; ".join(measures) + ".")
    u = report.get("unbacked_better")
    near = report.get("closest_rejected")
    if near is not None and u is None:
        sizes = _sizes(near["params"])
        s.append(f"The closest plausible explanation is {' and '.join(near['effects'])} "
                 f"({sizes}; cross-validated {near['rmse_cv_deg']:.2f} deg), not selected: "
                 + "; ".join(near["why_not"]) + ".")
    for c in report["candidates"]:
        if c.get("stands_in_for") and c.get("stands_in_because") == "replicate scatter":
            s.append(f"{' and '.join(c['effects'])} fits with plausible, significant values, "
                     f"but {_sized(report['candidates'], c['stands_in_for'])} fits better "
                     "while its size is within what replicate scatter explains: not "
                     "selected, for it would "
                     "stand in for an explanation these data cannot size. Measure more "
                     "specimens, or measure directly: " + "; ".join(
                         EFFECTS[e].measure_directly for e in [*c["effects"],
                                                               *c["stands_in_for"]]) + ".")
        elif c.get("stands_in_for"):
            s.append(f"{' and '.join(c['effects'])} fits with plausible, significant values, "
                     f"but {' and '.join(c['stands_in_for'])} fits better: not selected, "
                     "for it would stand in for an explanation the baseline cannot judge.")
        if c.get("outdone_by"):
            s.append(f"{' and '.join(c['effects'])} would leave a residual only the "
                     "baseline's own uncertainty at its fitted design excuses, while "
                     f"{' and '.join(c['outdone_by'])} fits better: not selected.")
    if u is not None:
        sizes = _sizes(u["params"])
        s.append(f"{' and '.join(u['effects'])} fits the data best ({sizes}; cross-validated "
                 f"error {u['rmse_cv_deg']:.2f} deg"
                 + (f", better than {' and '.join(u['instead_of'])}" if u["instead_of"]
                    else "") + "), but the baseline cannot back that size: "
                 + (f"its own uncertainty at the fitted design is "
                    f"{u['baseline_sd_at_fit_deg']:.2f} deg RMS"
                    if u["baseline_sd_at_fit_deg"] is not None else
                    f"its band at the nominal design is {report['baseline_sd_deg']:.2f} deg "
                    f"RMS and its pressure scale is known to {100 * PRESSURE_SCALE_SD:g} % "
                    "only")
                 + ", so its better fit may be the baseline's own error there. An FE solve "
                 "of the design (`balloon solve`) or a baseline with more FE data there "
                 "would decide.")
    beyond = report.get("wants_specimens_beyond")
    if beyond is not None:
        sizes = _sizes(beyond["params"])
        added = " and ".join(beyond["added"])
        s.append(f"{' and '.join(beyond['effects'])} fits better ({sizes}; BIC "
                 f"{-beyond['delta_bic_vs_selected']:.0f} lower, cross-validated "
                 f"{beyond['rmse_cv_deg']:.2f} deg, {added} significant beside it), not "
                 f"selected: {beyond['why_not'][0]}; with more specimens the data may show "
                 f"{added} acting too.")
    said = gauge_zero_sentence(report.get("gauge_at_rest"), report["selected_effects"])
    if said:
        s.append(said)
    runs_differ = first_run_sentence(report.get("first_run_against_later"))
    if runs_differ:
        s.append(runs_differ)
    for c in report["not_identifiable"]:
        if c["effect"] == "viscoelastic_creep" and report["data"]["has_time_s"]:
            s.append(f"Creep cannot be identified from these data ({c['reason']}): "
                     f"{c['measure']}.")
    data = report["data"]
    held = held_sentence(report.get("history_read_as_hold"))
    if held:
        s.append(held)
    if ("viscoelastic_creep" in report["selected_effects"] and not data.get("pump_logged")
            and data["readings"]["unloading"] and "measured" not in data["injected_volume"]):
        s.append(f"The creep is read from a history taken off the readings "
                 f"({data['readings']['loading']} loading, {data['readings']['hold']} hold, "
                 f"{data['readings']['unloading']} unloading): a hold in which a leak lets "
                 "the bend fall reads as unloading too, and creep then stands in for the "
                 "leak. If the pump held where this history has it withdraw, give its log "
                 "(the pump column: load, hold or unload before each reading, "
                 "docs/measured-data.md).")
    if left["structured"] and u is not None:
        size = left["unexplained_rms_deg"]
        s.append("What is left" + (f" ({size:.2f} deg RMS beyond the floor)" if size else "")
                 + " is what that effect would explain.")
    elif left["structured"] and _wants_specimens(near, left, noise):
        s.append(f"What remains is NOT noise ({left['unexplained_rms_deg']:.2f} deg RMS beyond "
                 f"the floor), but it is what {' and '.join(near['effects'])} would explain "
                 f"(cross-validated {near['rmse_cv_deg']:.2f} deg against the floor's "
                 f"{noise:.2f} deg): not an effect outside the catalogue, a set too large "
                 "for these specimens to back. Measure more specimens.")
    elif left["structured"]:
        s.append(left["sentence"])
        if report["pressure_channel"]["used"] and not report["data"].get("pump_logged"):
            s.append("The pump's history was read off the readings: a hold in which the "
                     "bend and the gauge fall (a fast leak) reads as unloading. If the pump "
                     "held or reversed where the report's history does not say so, give "
                     "its log (the pump column: load, hold or unload before each reading, "
                     "docs/measured-data.md).")
    elif noise is not None:
        at_fit = report["baseline_sd_after_deg"]
        if report["residual_within_baseline_band"]:
            s.append(f"What remains ({report['rmse_after_deg']:.2f} deg RMS, cross-validated) "
                     f"is more than replicate scatter (floor {noise:.2f} deg) but within the "
                     f"baseline's own uncertainty at this design (its band, {at_fit:.2f} deg "
                     "RMS): these data cannot tell an effect the selection lacks from the "
                     "baseline's own error here. An FE solve of the design (`balloon "
                     "solve`) would decide.")
        elif at_fit > 1.5 * report["baseline_sd_deg"] and at_fit > 0.25 * noise:
            s.append("What remains is consistent with replicate scatter and the baseline's "
                     f"own uncertainty at the fitted design ({at_fit:.2f} deg RMS): an FE "
                     "solve of that design (`balloon solve`) would sharpen the size.")
        elif gauge_sentence(report["gauge_left_after"]) is None and not runs_differ:
            s.append("What remains is consistent with replicate scatter (no structure along "
                     "the curves).")
        else:
            s.append("The angle's residual is consistent with replicate scatter (no "
                     "structure along the curves).")
    at_rest = report.get("gauge_at_rest")
    gauge = gauge_sentence(report["gauge_left_after"], bool(at_rest and at_rest["off"]),
                           (at_rest or {}).get("zeroed"))
    if gauge is not None:
        s.append(gauge)
    for w in report["warnings"]:
        s.append(f"Warning: {w}.")
    read = report["data"]["columns_read"]
    if read:
        s.append("Columns read: " + "; ".join(r["reading"] for r in read) + ".")
    clocks = report["data"].get("clock_columns")
    if clocks:
        s.append("Timestamps: " + "; ".join(c["reading"] for c in clocks) + ".")
    extra = report["data"].get("columns_not_read")
    if extra:
        s.append("Columns not read: " + "; ".join(c["reading"] for c in extra) + ".")
    out = report["left_out"]
    if out is not None and report["selected_effects"]:
        s.append(f"Of the {out['readings']} readings left out, the calibrated model answers "
                 + (f"{out['answered']}, to {out['rmse_deg']:.2f} deg RMS (readings its fit "
                    "never saw)." if out["answered"] else "none either."))
    return " ".join(s)


def _sized(candidates: list[dict], effects: list[str]) -> str:
    """``effects`` named with their fitted sizes, from their own candidate's fit when the
    report holds it ("membrane_stiffness (membrane_mu_scale = 1.05 +/- 0.03)")."""
    fit = next((c for c in candidates if list(c["effects"]) == list(effects)
                and c.get("params")), None)
    names = " and ".join(effects)
    if fit is None:
        return names
    return f"{names} ({_sizes(fit['params'])})"


def _sizes(params: dict) -> str:
    """Fitted parameters in words, with their units (none for a ratio, unit "-"):
    "membrane_mu_scale = 1.05 +/- 0.03, ..."."""
    return ", ".join(f"{n} = {p['value']:.3g} +/- {p['sd']:.2g}"
                     + ("" if p["unit"] == "-" else f" {p['unit']}") for n, p in params.items())


def _wants_specimens(near: dict | None, left: dict, noise: float | None) -> bool:
    """Whether the closest rejected set fails only for want of specimens (k + 2) and
    leaves no more than replicate scatter (its cross-validated error within the floor's
    allowance): then what is left is that set's, not an effect outside the catalogue
    (benchmarks/lab_rig_sets.py N25: an inlet of 100 Pa per ul/s with 2 ul/kPa of air,
    0.74 deg against a floor of 0.70 deg from 3 specimens, had been called outside it)."""
    return bool(near is not None and near.get("wants_specimens") and noise
                and left.get("excess_allowance")
                and near["rmse_cv_deg"] <= left["excess_allowance"] * noise)
