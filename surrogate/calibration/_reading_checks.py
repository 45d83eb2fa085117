"""Which readings the baseline can be compared with, and warnings about the rest:
readings past the end of the FE's range for their nominal design (by gauge pressure or
by injected volume) are left out with a warning naming the field, a design the baseline
cannot answer is refused, and angles that look like radians or of the opposite sign are
named. At least MIN_CURVES curves of 4 readings each must be left."""

from __future__ import annotations

import math

import numpy as np

from solver.errors import InputError
from surrogate.calibration._data import Observations
from surrogate.calibration._errors import DataError
from surrogate.calibration._response import Responses, design_key
from surrogate.calibration._start import Baseline

MIN_CURVES = 2  # curves (or specimens) the fit and its cross-validation need
RADIANS_MAX = 2.1  # |angle| in radians of a bend up to 120 deg
SIGN_SHOWN_DEG = 5.0   # the baseline bends at least this much where a sign is compared


def sign_warning(y: np.ndarray, pred: np.ndarray) -> str | None:
    """A warning when the measured angles have the opposite sign of the baseline's at
    most readings where it bends clearly (a protocol that measures positive towards the
    membrane): the catalogue has no sign flip, and the loop otherwise reports a 25 deg
    misfit that "no catalogued effect" explains."""
    shown = np.isfinite(pred) & (np.abs(pred) >= SIGN_SHOWN_DEG) & np.isfinite(y)
    if shown.sum() < 4:
        return None
    opposite = np.sign(y[shown]) == -np.sign(pred[shown])
    if opposite.mean() < 0.8:
        return None
    way = "away from" if np.median(pred[shown]) > 0 else "towards"
    return (f"angle_deg: at {int(opposite.sum())} of {int(shown.sum())} readings where the "
            f"baseline bends {SIGN_SHOWN_DEG:g} deg or more the angle has the opposite sign; "
            f"angle_deg is positive away from the membrane (these designs bend {way} it): "
            "if your protocol counts the other way, change the sign of angle_deg")


def radians_warning(y: np.ndarray, pred: np.ndarray) -> str | None:
    """Angles that look like radians: none beyond RADIANS_MAX while the baseline bends
    beyond 20 deg at those readings, and the data scale to the baseline's by about
    pi / 180 (least squares, within a factor 2)."""
    ok = np.isfinite(pred)
    if not np.any(ok) or np.max(np.abs(y)) > RADIANS_MAX or np.max(np.abs(pred[ok])) < 20.0:
        return None
    k = float(y[ok] @ pred[ok] / (pred[ok] @ pred[ok]))
    if not 0.5 < k * 180.0 / math.pi < 2.0:
        return None
    top = float(np.max(np.abs(y)))
    return (f"angle_deg: angles reach only {top:.3g} while the baseline bends "
            f"{float(np.max(np.abs(pred[ok]))):.0f} deg at these readings: they look like "
            f"radians (x57.3 gives {math.degrees(top):.0f} deg); convert angle_deg to "
            "degrees")


def table_end_pa(predictor, designs: dict, p_max_pa: float) -> float:
    """Where the baseline's pressure table ends: ``p_max_pa`` (1.6 x the largest reading),
    but no further than twice the highest pressure at which the baseline answers any of
    the ``designs``. One reading far past the FE's range (a typo of 1e6 Pa) would
    otherwise stretch the table's 241 steps over it, so that every curve fell between its
    first two points and was dropped as past the baseline's range; now that reading alone
    is (with a warning naming pressure_pa)."""
    probe = np.concatenate([[0.0], np.geomspace(1.0, max(p_max_pa, 2.0), 400)])
    answered = 0.0
    for d in designs.values():
        try:
            a = np.asarray(predictor.predict(d, probe).angle_deg, dtype=float)
        except InputError:
            continue
        finite = np.flatnonzero(np.isfinite(a))
        if finite.size:
            answered = max(answered, float(probe[finite[-1]]))
    return min(p_max_pa, 2.0 * answered) if answered > 0.0 else p_max_pa


def usable_rows(obs: Observations, responses: Responses, baseline: Baseline,
                warnings: list[str], by_gauge: bool = True
                ) -> tuple[Observations, np.ndarray]:
    """Refuse a design the baseline cannot answer and pressures where it overflows; drop
    (with a warning) readings past the end of its range at their gauge pressure (the FE
    stopped there: no number to compare with) when ``by_gauge``. Returns the readings
    kept and which rows of ``obs`` they are."""
    pred = np.empty(obs.n)
    for c in range(obs.n_curves):
        rows = np.flatnonzero(obs.curve == c)
        d = obs.design(c)
        try:
            out = baseline.predictor.predict(d, np.clip(obs.pressure_pa[rows], 0.0, None))
        except InputError as exc:
            raise InputError("model", f"the baseline {baseline.name!r} has no answer for "
                             f"curve {obs.curve_ids[c]!r} (L_mm = {d.L_mm:g}, t_mm = "
                             f"{d.t_mm:g}, {d.body_material.id}/{d.membrane_material.id}): "
                             f"{exc}", "a model covering every design of the data "
                             "(--model)") from None
        pred[rows] = np.asarray(out.angle_deg, dtype=float)
    # the fit reads the baseline off its table (linear between 241 pressures): a reading
    # in the last interval before the FE's end has no tabulated neighbour above it
    index = np.array([responses.index[design_key(obs.design(c))]
                      for c in range(obs.n_curves)])[obs.curve]
    tabulated = responses.lookup(responses.table(())[1], index,
                                 np.clip(obs.pressure_pa, 0.0, None))
    pred = np.where(np.isinf(pred) | np.isfinite(tabulated), pred, np.nan)
    inf = np.isinf(pred)
    if np.any(inf):
        i = int(np.flatnonzero(inf)[np.argmin(obs.pressure_pa[inf])])
        c = int(obs.curve[i])
        p_ok = np.abs(obs.pressure_pa[~inf & (obs.curve == c)])
        raise DataError("pressure_pa", f"curve {obs.curve_ids[c]!r}: the baseline "
                        f"{baseline.name!r} has no finite angle at {obs.pressure_pa[i]:g} Pa "
                        "(its exponential overflows)", None,
                        "pressures where the baseline is finite"
                        + (f" (up to {p_ok.max():.0f} Pa in this curve)" if p_ok.size else ""))
    ok = np.isfinite(pred) | (not by_gauge)
    return keep_within_range(obs, ok, "pressure_pa", "readings", "", warnings)


def within_volume_range(obs: Observations, responses: Responses, warnings: list[str]
                        ) -> tuple[Observations, np.ndarray]:
    """Drop (with a warning) readings whose injected volume lies past the end of the
    baseline's range for their nominal design."""
    index = np.array([responses.index[design_key(obs.design(c))]
                      for c in range(obs.n_curves)])[obs.curve]
    ok = np.ones(obs.n, bool)
    for what in ("angle_v", "pressure_v"):
        ok &= np.isfinite(responses.lookup_volume(responses.curves((), [], what), index,
                                                  obs.volume_ul))
    field = "volume_ul" if np.all(obs.volume_measured) else "time_s"
    return keep_within_range(obs, ok, field, "readings' injected volumes",
                             " of injected volume", warnings)


def keep_within_range(obs: Observations, ok: np.ndarray, field: str, what: str,
                      axis: str, warnings: list[str]) -> tuple[Observations, np.ndarray]:
    """The readings ``ok`` (inside the baseline's range for their design) and which rows
    of ``obs`` they are, with a warning naming ``field`` when some are dropped; curves
    left with fewer than 4 readings go too, and fewer than MIN_CURVES curves is a
    DataError on ``field``."""
    if np.all(ok):
        return obs, np.ones(obs.n, bool)
    warnings.append(f"{field}: {int((~ok).sum())} {what} lie past the end of the FE's "
                    "range for their nominal design (the baseline has no number there) and "
                    "are left out of the fit")
    keep_curves = [c for c in range(obs.n_curves) if np.sum(ok[obs.curve == c]) >= 4]
    kept = ok & np.isin(obs.curve, keep_curves)
    out = obs.rows(kept)
    if out.n_curves < MIN_CURVES:
        hint = ("; does time_s count from the pump's start, the chamber at rest? (the "
                "injected volume is flow x time_s)" if field == "time_s" else "")
        raise DataError(field, f"{out.n_curves} of {obs.n_curves} curves keep 4 readings "
                        f"within the baseline's range{axis} (the FE's converged "
                        f"range){hint}", None,
                        "at least 2 curves with 4 readings each below the end of the FE's "
                        "range")
    if out.n_specimens < MIN_CURVES:   # the runs of one specimen are left: as replicates
        out = out.as_replicates()
    return out, kept
