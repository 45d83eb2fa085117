"""The gauge pressure after a selection, where the data are read by injected volume
(the angle and the gauge pressure both against the pump's volume): its cross-validated
RMS error (Pa) against its replicate floor, whether a set must leave it within that floor
(a set read off the gauge, or one that moves the gauge the wrong way), and the sentence
that says what is left there."""

from __future__ import annotations

import numpy as np

from surrogate.calibration._least_squares import (
    CrossValidation,
)
from surrogate.calibration._report_tables import finite_or_none
from surrogate.calibration.effects import EFFECTS

GAUGE_LEFT_RATIO = 1.3   # the gauge's cross-validated error over its replicate floor


def reads_gauge(effects: tuple[str, ...]) -> bool:
    """A set with a member of the gauge alone (its pressure stage: offset, gain, the
    inlet's R Q; or a time effect of the gauge: relaxation, drift): its size is read off
    the gauge, so it must leave the gauge within its floor (``gauge_left``) to be
    selected. Until 2026-12-06 only the angle's residual was asked: a kink forming in the
    tubing mid-run (its R Q from 0 to 300 Pa per ul/s) was read as an inlet resistance
    of 209 +/- 1 Pa per ul/s with a gauge offset of -112 Pa, the gauge left at 5.6 x its
    floor (said, but the sizes reported as found)."""
    return any(EFFECTS[e].stage == "pressure" or EFFECTS[e].lags == "gauge" for e in effects)


def gauge_worse(rmse_pa: float | None, base_pa: float | None) -> bool:
    """A set that moves the gauge against the injected volume (a line's compliance, a
    leak, a physical change) and predicts it worse than the baseline does: it must then
    leave the gauge within its floor as a gauge effect must (``gauge_left``). Such an
    effect changes the chamber's pressure and bend together; where only the bend moves,
    its fit to the bend pays in the gauge. Until 2026-12-07 a camera whose time stamps
    were 0.5 s late (outside the catalogue: the bend lags, the gauge does not) was
    read as air in the line, C 1.26 +/- 0.10 ul/kPa, the gauge taken from 96 to 119 Pa
    against an 80 Pa floor (benchmarks/lab_rig_sets.py N13)."""
    return rmse_pa is not None and base_pa is not None and rmse_pa > base_pa


def gauge_left(rmse_pa: float | None, channel: dict, allowance: float | None
               ) -> dict | None:
    """Whether the gauge pressure is left above its replicate floor after the selected effects, by
    more than GAUGE_LEFT_RATIO and the angle's excess allowance for these data (``_residual``: how
    well the floor is known from these replicates; the plain error's, ``plain_allowance``, as the
    gauge's own is plain: the angle's net of the baseline's band divides by what the band leaves,
    and on a clean-looking set where the band took nearly all of it, Mullins softening read as a
    gauge drift, it was 4.41, so a gauge left at up to 4.4 x its floor passed), None when the gauge
    is not read as an observable. The structure test reads the angle only, so a misfit of the
    pressure alone (it relaxes at constant volume, a line that is compliant or leaks) was reported
    as "consistent with replicate scatter" (53.5 Pa against a 38.7 Pa floor, an independent lab set
    of 2026-12-05; its clean sets 0.92-1.06 x their floor)."""
    floor = channel.get("pressure_floor_pa")
    if rmse_pa is None or not floor:
        return None
    limit = max(GAUGE_LEFT_RATIO, allowance or 0.0)
    ratio = rmse_pa / floor
    return {"rmse_pa": rmse_pa, "floor_pa": floor, "ratio": ratio, "limit": limit,
            "left": bool(ratio > limit)}


def gauge_sentence(gauge: dict | None, zero_off: bool = False,
                   zeroed: dict | None = None) -> str | None:
    """The interpretation's sentence on a gauge left above its floor (``gauge_left``).
    ``zero_off``: the gauge's zero was found off at rest (``_gauge_zero``), a catalogued
    effect the whole curves did not select: the sentence then names it as part of what is
    left rather than saying no catalogued effect explains it (N53 of the forty-ninth
    session's lab sets, a +30 Pa zero, said both). ``zeroed``: the selection made again
    with that zero taken off every gauge reading (``_gauge_zero.zeroed_summary``): the
    sentence then says what the gauge is left with there, within its floor (the zero and
    that selection explain it) or not (something besides the zero acts on it)."""
    if not gauge or not gauge["left"]:
        return None
    head = (f"The gauge pressure is left at {gauge['rmse_pa']:.0f} Pa RMS (cross-validated) "
            f"against its replicate floor of {gauge['floor_pa']:.0f} Pa ({gauge['ratio']:.2f} "
            f"x, more than the {gauge['limit']:.2f} x scatter allows here)")
    after = (zeroed or {}).get("gauge_left_after")
    if zero_off and after:
        sel = " and ".join(zeroed["selected_effects"]) or "nothing"
        there = (f" as the readings are written; with the zero found at rest taken off "
                 f"every reading ({sel} selected then) it is left at {after['rmse_pa']:.0f} "
                 f"Pa ({after['ratio']:.2f} x its floor")
        if not after["left"]:
            return (head + there + f", within the {after['limit']:.2f} x scatter allows): "
                    "the zero" + ("" if sel == "nothing" else f" and {sel}")
                    + " explain what the gauge is left with.")
        return (head + there + f", still more than the {after['limit']:.2f} x scatter "
                "allows): besides the zero, something acts on the pressure that no "
                "catalogued effect explains (a gauge drifting with time or temperature, or "
                "a relaxation, leak or compliance of another form than the catalogue's).")
    if zero_off:
        return (head + ": part of it is the gauge's zero found off at rest (above); zero "
                "the gauge and calibrate again to see whether anything acts on the pressure "
                "besides it (a gauge drifting with time or temperature, or a relaxation, "
                "leak or compliance of another form than the catalogue's).")
    return (head + ": something acts on the pressure that no catalogued effect explains (a "
            "gauge drifting with time or temperature, or a relaxation, leak or compliance "
            "of another form than the catalogue's); sizes read from the gauge may carry "
            "part of it.")


def pressure_rms_pa(xv: CrossValidation, channel: dict) -> float | None:
    """Cross-validated RMS error of the gauge pressure at the injected volume (Pa)."""
    if xv.pressure is None or not channel["used"]:
        return None
    return finite_or_none(float(np.sqrt(np.nanmean(xv.pressure**2))) / channel["weight_deg_per_pa"])


def gauge_gain_clause(report: dict) -> str:
    """What the selection does to the gauge's error, said where the angle's is above the
    baseline's (by volume only: rule 5 lets it be where held-out curves do not tell the
    two apart, the gauge's error falling)."""
    before, after = report.get("rmse_pressure_before_pa"), report.get("rmse_pressure_after_pa")
    if before is None or after is None or report["rmse_after_deg"] <= report["rmse_before_deg"]:
        return ""
    return (f" (the angle's, {report['rmse_before_deg']:.2f} deg before: held-out curves do "
            f"not tell the two apart) and the gauge's {after:.0f} Pa, {before:.0f} Pa before")
