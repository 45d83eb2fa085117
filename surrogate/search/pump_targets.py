"""A syringe pump's targets in the design search: by injected volume, or by time at a flow
rate (time = volume / flow from the undeformed state, as the predictor's answers by time).

A pump's target (``DesignTarget.by_volume``: angle_at_volume, volume_budget,
angle_at_time, time_budget) is met at an injected volume (ul, whole actuator); the search
screens designs by the model's own answers by volume: the angle with its band at the
target volume and the volume needed for the target angle with its band (the emulator's
``evaluate_designs_by_volume``, many at once; any other model's ``predict_volume`` and
``inverse`` one design at a time). Nothing past a design's FE range is answered (NaN), so
no such design is listed. A listed design reports what a pump user sets and reads
(``volume_report``): the volume (and at the flow rate the time) needed for the angle,
with its band, and the angle with its band and the chamber pressure at the target volume.
"""

from __future__ import annotations

import numpy as np

from solver.design import Design
from solver.errors import InputError
from surrogate.predictor import InversePrediction, Prediction
from surrogate.search.design_target import DesignTarget
from surrogate.volume_control import cut_past_longest_time

#: volumes tried below the target's, as fractions of it, for a design's bending direction
#: where the target volume is past its FE range
LOWER_VOLUME_FRACTIONS = (0.5, 0.25, 0.125)


def ask(model: object, design: Design, target: DesignTarget, at: object, level: float
        ) -> Prediction:
    """The model's answer for ``design`` at ``at``: pressures (Pa) for a target by
    pressure, injected volumes (ul) for a pump's target."""
    if target.by_volume:
        return model.predict_volume(design, at, level=level)  # type: ignore[attr-defined]
    return model.predict(design, at, level=level)  # type: ignore[attr-defined]


def require_volumes(model: object, target: DesignTarget) -> None:
    """InputError naming ``kind`` where ``model`` gives no answers by injected volume."""
    if not hasattr(model, "predict_volume"):
        raise no_volume_error(model, target)


def no_volume_error(model: object, target: DesignTarget) -> InputError:
    """A pump's target asked of a model with no injected volume (for the designs inside
    the bounds): refused naming ``kind``, never answered "not reachable"."""
    return InputError("kind", f"the model {getattr(model, 'name', '')!r} gives no injected "
                      f"volume for the designs inside the bounds: no {target.kind} target",
                      'model "emulator" (or an exponential model fitted from FE curves '
                      "with volumes) for a pump's target; angle_at_pressure, "
                      "pressure_budget or force_at_pressure with this model")


def screen_by_volume(model: object, designs: list[Design], target: DesignTarget,
                     level: float, band: bool = True) -> dict[str, np.ndarray]:
    """For every design: |angle| (deg) with its band at the target volume (``value``),
    the injected volume (ul) needed for the target angle with its band (``needed``) and
    the bending direction (``sign``), NaN where the model has no answer (past the FE's
    range); the keys of ``screen.screen``, and ``no_volume`` where the model
    gives no volume for the design (the paper's families). ``band=False``: the batch
    reads the means alone (bands NaN), for a bisection step."""
    batch = getattr(model, "evaluate_designs_by_volume", None)
    if batch is not None:
        out = batch(designs, target.at, target.value, level, band)
        return {"value": np.abs(out["angle"]), "value_lo": np.fmin(out["angle_lo"],
                                                                   out["angle_hi"]),
                "value_hi": np.fmax(out["angle_lo"], out["angle_hi"]),
                "needed": out["needed"], "needed_lo": out["needed_lo"],
                "needed_hi": out["needed_hi"], "sign": out["sign"]}
    require_volumes(model, target)
    keys = ("value", "value_lo", "value_hi", "needed", "needed_lo", "needed_hi", "sign")
    res = {k: np.full(len(designs), np.nan) for k in keys}
    res["no_volume"] = np.zeros(len(designs), bool)  # the model has no volume for it
    for i, design in enumerate(designs):
        try:
            pred = ask(model, design, target, [target.at], level)
        except InputError as exc:
            res["no_volume"][i] = exc.field == "volumes_ul"
            continue
        vals = np.abs([pred.angle_deg[0], pred.lower_deg[0], pred.upper_deg[0]])
        sign = _sign(model, design, target, pred, level)
        res["sign"][i] = sign
        finite = vals[np.isfinite(vals)]
        res["value"][i], res["value_lo"][i], res["value_hi"][i] = (
            vals[0], *((finite.min(), finite.max()) if finite.size else (np.nan, np.nan)))
        try:
            inv = model.inverse(design, [(sign or 1.0) * target.value],  # type: ignore
                                level=level)
        except InputError:
            continue
        if inv.volume_ul is not None:
            res["needed"][i] = inv.volume_ul[0]
            res["needed_lo"][i], res["needed_hi"][i] = sorted(
                (inv.volume_lower_ul[0], inv.volume_upper_ul[0]))  # type: ignore[index]
    return res


def _sign(model: object, design: Design, target: DesignTarget, pred: Prediction,
          level: float) -> float:
    """+1 / -1: which way ``design`` bends, read at the target volume or, past its FE
    range there, at the first answered of LOWER_VOLUME_FRACTIONS of it; 0 when none is."""
    angle = float(pred.angle_deg[0])
    if np.isfinite(angle) and angle != 0:
        return float(np.sign(angle))
    low = ask(model, design, target, target.at * np.array(LOWER_VOLUME_FRACTIONS),
              level).angle_deg
    found = [a for a in low if np.isfinite(a) and a != 0]
    return float(np.sign(found[0])) if found else 0.0


def volume_report(model: object, design: Design, target: DesignTarget,
                  inv: InversePrediction, level: float, validity: dict
                  ) -> dict[str, float | None]:
    """What a listed design gives a pump user: the injected volume needed for the target
    angle with its band (ul; ``inv``, the model's inverse at the signed target angle, which
    the caller reads the pressure needed off too), at the flow rate the time (s), and at
    the target volume the signed angle with its band (deg) and the chamber pressure (Pa);
    None where the model has no number (past the design's FE range: a budget's design
    may get there before the budget; said in ``validity``'s messages, in place)."""
    def number(x: object) -> float | None:
        return float(x) if x is not None and np.isfinite(x) else None  # type: ignore

    v = [None if a is None else number(a[0])
         for a in (inv.volume_ul, inv.volume_lower_ul, inv.volume_upper_ul)]
    at = ask(model, design, target, [target.at], level)
    out: dict[str, float | None] = {
        "volume_needed_ul": v[0], "volume_lower_ul": v[1], "volume_upper_ul": v[2],
        "angle_at_volume_deg": number(at.angle_deg[0]),
        "angle_at_volume_lower_deg": number(at.lower_deg[0]),
        "angle_at_volume_upper_deg": number(at.upper_deg[0]),
        "pressure_at_volume_pa": number(at.pressure_pa[0])}
    if out["angle_at_volume_deg"] is None:
        end = at.validity.get("fe_limit_volume_ul")
        validity["messages"].append(
            f"no angle at {target.at:.4g} ul: the design's FE range ends "
            + (f"at {end:.4g} ul" if end is not None else "before it")
            + " (the target is met before it: volume_needed_ul)")
    if target.flow_ul_s is not None:   # no time past the longest pump time, as by time
        times = {name: [None if x is None else x / target.flow_ul_s] for name, x in
                 zip(("time_needed_s", "time_lower_s", "time_upper_s"), v, strict=True)}
        cut_past_longest_time(times, validity, tuple(times), target.flow_ul_s, "time(s)",
                              "volume_needed_ul and its band are the fluid needed")
        out.update({name: t[0] for name, t in times.items()})
    return out
