"""The gauge at rest: its zero read off the data directly, whatever the actuator.

Before the pump has put any volume in (injected volume 0, at or before the curve's
start), the chamber is at rest and its pressure is 0 Pa whatever the design, the
specimen's stiffness or the loading history; a gauge reading there is the gauge's own
zero. The calibrated model's gauge at those readings is what it claims the zero is (0 Pa,
or a selected pressure offset), so each curve's mean difference at rest, the curves the
units (a gauge zeroed once per run shares it along the run), is tested with Student's t
at ``LEVEL`` (two-sided, n_curves - 1 degrees of freedom).

Why it is asked apart from the fit: over a whole curve the specimens' own stiffness moves
the gauge by a few per cent of the pressure (7 % scatter: +-150 Pa at 2 kPa), and a
least-squares offset over every reading is then the specimens' mean stiffness more than
the gauge's zero. On a lab's three PDMS 1:10 specimens read by a gauge 60 Pa high
(benchmarks/lab_rig_sets.py L9) the fitted offset was -50 +/- 77 Pa and nothing was
selected, while the three readings at rest said 56, 57 and 65 Pa. Weighting the fit for
that scatter (_specimens.py along the gauge channel) gives 56 +/- 6 Pa but does not pass
the selection (BIC against a noise read as one sd for every reading: the gauge's 1.5 %
noise at the top, 2 Pa at rest), so the loop says what the readings at rest show and
leaves the selection as it is.

With an inlet resistance selected the question is not asked: R Q at a reading taken as the
pump starts is not defined by the readings.

A zero that is off biases whatever else the selection reads off the gauge: a pressure gain
fitted over whole curves takes up part of it. So when the zero is off and a gauge effect
other than an offset is selected, the loop does what the report asks of the lab -- takes
the zero (the mean at rest) off every gauge reading and selects again -- and says beside
the selection whether that effect remains and at what size (``zeroed``). The selection
itself stays the one the readings as written give (a zero subtracted is a choice the lab
confirms by zeroing its gauge). On three soft PDMS 1:15 specimens of a reversed pair read
by a gauge 60 Pa high (lab_rig_sets.py N2, the batch 9.1 % soft) the gain selected is
0.936 +/- 0.012; with the +59 Pa zero taken off, 0.914 +/- 0.012.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import t as student_t

LEVEL = 0.01          # two-sided: a clean lab's zero is said to be off in 1 set of 100
MIN_CURVES = 3        # a mean and a spread from at least two degrees of freedom
# the curves' spread at rest is taken at least this (Pa): a gauge written in kPa to three
# decimals reads to 1 Pa, and three curves that happen to agree to the digit (sd 0) must
# not make a 2 Pa zero "off" at an infinite t
MIN_SD_PA = 1.0


def gauge_at_rest(curve: np.ndarray, volume_ul: np.ndarray, gauge_pa: np.ndarray,
                  model_pa: np.ndarray) -> dict | None:
    """The readings at rest (injected volume 0, before any volume was injected on their
    curve: rows in history order, by time or, without time, the file's) against the
    model's gauge there (Pa): None with fewer than MIN_CURVES curves read at rest; else
    the mean difference, its se, t, the critical t and ``off``. A pump's volume log
    without time places them too (until 2026-12-07 only a ``time_s`` did: a gauge 50 Pa
    low went unsaid, benchmarks/lab_rig_sets.py N29)."""
    d = gauge_pa - model_pa
    per_curve = []
    for c in np.unique(curve):
        rows = np.flatnonzero(curve == c)
        pumped = np.flatnonzero(volume_ul[rows] > 0.0)
        before = rows[:pumped[0]] if pumped.size else rows
        rest = before[(volume_ul[before] == 0.0) & np.isfinite(d[before])]
        if rest.size:
            per_curve.append(float(np.mean(d[rest])))
    n = len(per_curve)
    if n < MIN_CURVES:
        return None
    mean = float(np.mean(per_curve))
    se = float(max(np.std(per_curve, ddof=1), MIN_SD_PA) / np.sqrt(n))
    critical = float(student_t.ppf(1.0 - LEVEL / 2.0, n - 1))
    t = mean / se
    return {"curves": n, "mean_pa": mean, "se_pa": se, "t": float(t),
            "critical_t": critical, "off": bool(abs(t) > critical)}


def wants_zeroed_pass(rest: dict | None, selected: tuple[str, ...],
                      gauge: dict | None = None) -> bool:
    """Whether the selection is made again with the zero taken off: the zero is off and
    something other than a pressure offset alone is selected, or nothing is and the gauge
    is left above its floor (``gauge``, ``_gauge_check.gauge_left``): the whole curves
    are then read with the zero measured at rest applied, and what the gauge is left with
    said from that reading (until 2026-12-08 only a selection with a gauge effect other
    than the offset was read again, and N53 of the forty-ninth session's lab sets -- a
    +30 Pa zero, nothing selected -- said the zero at rest, +31 +/- 3 Pa, beside a gauge
    left at 1.88 x its floor and an offset over whole curves of -57 +/- 25 Pa, two
    opposite readings of one gauge). Nothing selected and the gauge within its floor
    leave nothing to read again: the second pass doubles the loop's time."""
    if rest is None or not rest["off"] or set(selected) == {"pressure_offset"}:
        return False
    return bool(selected) or bool(gauge and gauge["left"])


def zeroed_summary(report: dict) -> dict:
    """What the second pass selected, from its report: effects, sizes, errors and what
    the gauge is left with (``_gauge_check.gauge_left``)."""
    fitted = report["fitted"]["effects"]
    return {"selected_effects": list(report["selected_effects"]),
            "params": {n: {"value": p["value"], "sd": p["sd"], "unit": p["unit"]}
                       for n, p in fitted.items()},
            "rmse_after_deg": report["rmse_after_deg"],
            "rmse_pressure_after_pa": report["rmse_pressure_after_pa"],
            "gauge_left_after": report["gauge_left_after"]}


def whole_curve_offsets(candidates: list[dict]) -> dict | None:
    """The pressure offset the whole curves fit (Pa, value and sd), alone and beside a
    pressure gain when both were fitted: None when no offset candidate has a size. Over
    whole curves the specimens' mean stiffness moves the gauge in proportion to the
    pressure, and an offset alone takes it up (N53: -57 +/- 25 Pa for a +30 Pa zero, the
    batch 5 % soft); beside a gain it is the zero again (+36 +/- 3 Pa)."""
    def p0(effects: set[str]) -> dict | None:
        found = [c["params"].get("p0_pa") for c in candidates if set(c["effects"]) == effects]
        return ({"value_pa": found[0]["value"], "sd_pa": found[0]["sd"]}
                if found and found[0] and np.isfinite(found[0]["sd"] or np.nan) else None)
    alone = p0({"pressure_offset"})
    if alone is None:
        return None
    return {"alone": alone, "beside_gain": p0({"pressure_offset", "pressure_gain"})}


def _whole_curves_sentence(rest: dict) -> str:
    w = rest.get("whole_curves")
    if w is None or abs(w["alone"]["value_pa"] - rest["mean_pa"]) <= 2.0 * math.hypot(
            w["alone"]["sd_pa"], rest["se_pa"]):
        return ("Over whole curves the specimens' own stiffness moves the gauge far more "
                "than that, which is why no offset of this size was selected from them")
    gain = w["beside_gain"]
    beside = ("" if gain is None else
              f"; fitted with a gain beside it, {gain['value_pa']:+.0f} +/- "
              f"{gain['sd_pa']:.0f} Pa")
    return (f"Fitted over whole curves an offset alone reads {w['alone']['value_pa']:+.0f} "
            f"+/- {w['alone']['sd_pa']:.0f} Pa{beside}: there the specimens' own stiffness "
            "moves the gauge in proportion to the pressure, far more than the zero, and an "
            "offset alone takes that up. Trust the zero read at rest, where the actuator "
            "has no say")


def _zeroed_sentence(rest: dict, selected: list[str]) -> str:
    z = rest.get("zeroed")
    if z is None:
        return ""
    sel = " and ".join(z["selected_effects"])
    sizes = ", ".join(f"{n} = {p['value']:.3g} +/- {p['sd']:.2g}"
                      + ("" if p["unit"] == "-" else f" {p['unit']}")
                      for n, p in z["params"].items())
    head = (f" With that zero ({rest['mean_pa']:+.0f} Pa) taken off every gauge reading and "
            "the selection made again, ")
    if not sel:
        return head + ("nothing is selected: " + " and ".join(selected) + " stood in for "
                       "the zero.")
    if set(z["selected_effects"]) == set(selected):
        return head + (f"{sel} remains ({sizes}): it is not the zero's doing, and this is "
                       "its size once the gauge is zeroed.")
    return head + f"the selection is {sel} ({sizes}) instead."


def sentence(rest: dict | None, selected: list[str]) -> str | None:
    """What the interpretation says when the gauge's zero is off at rest (None if not)."""
    if rest is None or not rest["off"]:
        return None
    claim = ("the selected pressure offset" if "pressure_offset" in selected
             else "the model (0 Pa)")
    return (f"At rest, before the pump has put any volume in, the chamber's pressure is "
            f"0 Pa whatever the actuator, and the gauge reads {rest['mean_pa']:+.0f} +/- "
            f"{rest['se_pa']:.0f} Pa away from {claim} there ({rest['curves']} curves, "
            f"t {rest['t']:.1f} against {rest['critical_t']:.1f} at "
            f"{100 * LEVEL:g} %): its zero is off. " + _whole_curves_sentence(rest)
            + "; zero the gauge before each run (or subtract it) and calibrate again."
            + _zeroed_sentence(rest, selected))
