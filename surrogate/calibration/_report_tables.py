"""The report's tables: every reading with the fitted angle before and after the
selection (and the gauge pressure by volume), the readings left out past the FE's range
as the calibrated model predicts them, the refitted open parameters, and a per-family
exponential baseline's refitted constants. Numbers go to JSON: a value that is not
finite is written as null (``finite_or_none``)."""

from __future__ import annotations

import math

import numpy as np

from surrogate.calibration._data import Observations
from surrogate.calibration._least_squares import (
    FitResult,
)
from surrogate.calibration._start import Baseline
from surrogate.exponential.equations import TAU_FORM


def finite_or_none(x: float | None) -> float | None:
    """``x`` as a float for the JSON report, or None (null) when it is missing or not
    finite."""
    return float(x) if x is not None and math.isfinite(x) else None


def prediction_rows(obs: Observations, base: FitResult, after: FitResult) -> list[dict]:
    """Every reading the fit used, with the recalibrated baseline's and the selected
    effects' fitted angle there (deg; each at the reading's own flow rate and time) and,
    where the gauge is read against the injected volume, the gauge pressure the selected
    effects give (Pa): what a page or a script draws beside the data without saving."""
    before, fitted = base.angles(), after.angles()
    gauge = (after.model.gauge_pressures(after.x) if after.model.by_volume
             else np.full(obs.n, np.nan))
    return [{"curve_id": obs.curve_ids[int(c)], "pressure_pa": float(p),
             "angle_deg": float(a), "angle_before_deg": finite_or_none(float(b)),
             "angle_after_deg": finite_or_none(float(f)),
             "pressure_after_pa": finite_or_none(float(g)),
             "left_out": False}
            for c, p, a, b, f, g in zip(obs.curve, obs.pressure_pa, obs.angle_deg, before,
                                        fitted, gauge, strict=True)]


def left_out_check(all_obs: Observations, kept: np.ndarray, model_for, after: FitResult
                   ) -> tuple[dict | None, list[dict]]:
    """The readings left out of the fit as past the end of the FE's range for their
    nominal design, predicted by the calibrated model: a stiffer actuator reaches
    pressures past the nominal's 90 deg, and there the selected effects either predict
    the readings the fit never saw or do not. None when none were left out; ``answered``
    0 where the calibrated model has no number there either (or its parameters do not
    carry over: a curve left out whole took its own parameters with it). With it, the
    readings as ``predictions`` rows (``left_out`` true; no baseline angle: it has none
    there)."""
    if np.all(kept):
        return None, []
    out = {"readings": int((~kept).sum()), "answered": 0, "rmse_deg": None,
           "why": "past the end of the FE's range for their nominal design"}
    model = model_for(all_obs)
    pred = np.full(int((~kept).sum()), np.nan)
    if model.layout.names == after.model.layout.names:
        pred = model.angles(after.x)[~kept]
    err = pred - all_obs.angle_deg[~kept]
    ok = np.isfinite(err)
    if ok.any():
        out.update(answered=int(ok.sum()), rmse_deg=float(np.sqrt(np.mean(err[ok] ** 2))))
    rows = np.flatnonzero(~kept)
    return out, [{"curve_id": all_obs.curve_ids[int(all_obs.curve[i])],
                  "pressure_pa": float(all_obs.pressure_pa[i]),
                  "angle_deg": float(all_obs.angle_deg[i]), "angle_before_deg": None,
                  "angle_after_deg": finite_or_none(float(a)), "pressure_after_pa": None,
                  "left_out": True} for i, a in zip(rows, pred, strict=True)]


def open_table(obs: Observations, base: FitResult, after: FitResult) -> list[dict]:
    out = []
    for f, name in ((base, "before"), (after, "after")):
        for n, v, s in zip(f.model.layout.names[:f.model.layout.n_open],
                           f.x[:f.model.layout.n_open], list(f.sd().values()), strict=False):
            fam = obs.families[int(n[n.index("[") + 1:-1])]
            out.append({"fit": name, "parameter": n[4:n.index("[")], "family":
                        "/".join(map(str, fam[:2])), "scale": float(np.exp(v)),
                        "sd_log": finite_or_none(s)})
    return out


def family_constants(obs: Observations, baseline: Baseline, base: FitResult,
                     after: FitResult) -> dict:
    """For a per-family exponential baseline, the refitted constants: a' = k_A a and
    a_t' = k_p a_t (angle k_A f(p / k_p) is the model with tau x k_p), b_t and c as they
    were ("families", after; "baseline_before", before). Empty for other baselines."""
    fp = getattr(baseline.predictor, "family_parameters", None)
    if not baseline.open_parameters or not callable(fp):
        return {}
    out = {}
    for key, f in (("families", after), ("baseline_before", base)):
        k_a, k_p = f.model._scales(f.x)
        rows = []
        for i, fam in enumerate(obs.families):
            here = np.flatnonzero(obs.family == i)
            if not here.size:
                continue
            c = int(obs.curve[here[0]])
            par = fp(obs.design(c))
            rows.append({"body_material": fam[0], "membrane_material": fam[1],
                         "T_mm": fam[2], "b_mm": fam[3], "h_mm": fam[4],
                         "a_deg_per_mm": float(par["a_deg_per_mm"]) * float(k_a[here[0]]),
                         "a_t_pa": float(par["a_t_pa"]) * float(k_p[here[0]]),
                         "b_t_per_mm": float(par["b_t_per_mm"]),
                         "c": float(par.get("c", 0.0) or 0.0),
                         "tau_form": TAU_FORM})
        out[key] = rows
    return out
