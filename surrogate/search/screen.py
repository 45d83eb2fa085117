"""What a model answers for many candidate designs at a search's target: the screen.

For a target by pressure: |angle| (deg; |force|, mN, for a force target) with its band at
the target pressure (Pa), and the pressure (Pa) needed for the target angle with its
band; for a syringe pump's target the same by injected volume (ul:
``surrogate.search.pump_targets.screen_by_volume``). With each design's bending direction
(``sign``: +1 away from the membrane, -1 towards it, 0 unknown): the search matches
magnitudes, and a design bending against the target's direction is no candidate.
NaN wherever the model has no number (past a design's FE range, outside its domain).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.design import Design
from solver.errors import InputError
from surrogate.search.design_target import DesignTarget
from surrogate.search.pump_targets import screen_by_volume

#: the screen's numbers of a design, in the order ``Screened`` holds them
SCREENED_KEYS = ("needed", "needed_lo", "needed_hi", "value", "value_lo", "value_hi")


@dataclass
class Screened:
    """One candidate as screened: its pair, searched values (``space.VARIABLES``)
    and design; ``needed`` with its band: the pressure (Pa; a pump's target: the injected
    volume, ul) needed for the target angle; ``value`` with its band: |angle| (deg) or
    |force| (mN) at the target pressure (a pump's target: |angle| at the target volume)."""

    pair: tuple[str, str]
    values: dict[str, float]
    design: Design
    needed: float = np.nan
    needed_lo: float = np.nan
    needed_hi: float = np.nan
    value: float = np.nan
    value_lo: float = np.nan
    value_hi: float = np.nan

    @classmethod
    def from_screen(cls, pair: tuple[str, str], values: dict[str, float], design: Design,
                    screen_out: dict[str, np.ndarray], i: int) -> Screened:
        """The ``i``-th design of a ``screen`` output."""
        return cls(pair, values, design, *(float(screen_out[k][i]) for k in SCREENED_KEYS))


def target_direction(target: DesignTarget) -> float:
    """+1: the target bends away from the membrane; -1: towards it."""
    raw = target.force_mn if target.kind == "force_at_pressure" else target.angle_deg
    return -1.0 if float(raw) < 0 else 1.0  # type: ignore[arg-type]


def screen(model: object, designs: list[Design], target: DesignTarget, level: float,
           band: bool = True) -> dict[str, np.ndarray]:
    """|value| at the target pressure with its band, the pressure needed for the
    target angle with its band, and the design's bending direction (``sign``, +1 / -1,
    0 unknown), for every design (NaN where the model has no answer). Uses the model's
    batch ``evaluate_designs`` when it has one (the emulator), else its ``predict`` and
    ``inverse`` per design. ``band=False``: a pump's target's bands may be NaN (the
    emulator's batch then reads the means alone: a bisection step's)."""
    if target.by_volume:
        return screen_by_volume(model, designs, target, level, band)
    angle = None if target.kind == "force_at_pressure" else target.value
    batch = getattr(model, "evaluate_designs", None)
    if batch is not None:
        out = batch(designs, target.pressure_pa, angle, level)
        if target.kind == "force_at_pressure":
            out = {**out, "angle": np.abs(out["force"]), "angle_lo": np.abs(out["force_lo"]),
                   "angle_hi": np.abs(out["force_hi"])}
        lo = np.fmin(out["angle_lo"], out["angle_hi"])
        hi = np.fmax(out["angle_lo"], out["angle_hi"])
        return {"value": np.abs(out["angle"]), "value_lo": lo, "value_hi": hi,
                "needed": out["needed"], "needed_lo": out["needed_lo"],
                "needed_hi": out["needed_hi"], "sign": out["sign"]}
    res = {k: np.full(len(designs), np.nan) for k in (*SCREENED_KEYS, "sign")}
    res["no_force"] = np.zeros(len(designs), bool)
    for i, design in enumerate(designs):
        try:
            pred = model.predict(design, [target.pressure_pa], level=level)  # type: ignore
        except InputError:
            continue
        if target.kind == "force_at_pressure":
            if pred.force_mn is None:       # the model has no force for this design
                res["no_force"][i] = True
                continue
            vals = np.abs([pred.force_mn[0], pred.force_lower_mn[0], pred.force_upper_mn[0]])
            res["sign"][i] = np.sign(pred.force_mn[0]) if np.isfinite(pred.force_mn[0]) else 0
        else:
            vals = np.abs([pred.angle_deg[0], pred.lower_deg[0], pred.upper_deg[0]])
            sign = bending_sign(model, design, pred, target.pressure_pa, level)
            res["sign"][i] = sign
            try:
                inv = model.inverse(design, [(sign or 1.0) * target.value],  # type: ignore
                                    level=level)
                res["needed"][i] = inv.pressure_pa[0]
                res["needed_lo"][i], res["needed_hi"][i] = inv.lower_pa[0], inv.upper_pa[0]
            except InputError:
                pass
        finite = vals[np.isfinite(vals)]  # none past the FE's range: no band (nanmin warns)
        res["value"][i], res["value_lo"][i], res["value_hi"][i] = (
            vals[0], *((finite.min(), finite.max()) if finite.size else (np.nan, np.nan)))
    return res


def bending_sign(model: object, design: Design, pred: object, pressure_pa: float,
                 level: float) -> float:
    """+1 / -1: which way ``design`` bends (``pred``: its prediction at ``pressure_pa``;
    where that is past the FE's range, the first answered of a few lower pressures), 0
    when no pressure is answered."""
    angle = float(pred.angle_deg[0])  # type: ignore[attr-defined]
    if np.isfinite(angle) and angle != 0:
        return float(np.sign(angle))
    low = model.predict(design, pressure_pa * np.array([0.5, 0.25, 0.125]),  # type: ignore
                        level=level).angle_deg
    found = [a for a in low if np.isfinite(a) and a != 0]
    return float(np.sign(found[0])) if found else 0.0


def keep_direction(screen_out: dict[str, np.ndarray], direction: float) -> np.ndarray:
    """In place: no answer (NaN) for the designs of ``screen_out`` (``screen``) that bend
    against ``direction``; returns which those were."""
    wrong = screen_out["sign"] == -direction
    for k in SCREENED_KEYS:
        screen_out[k] = np.where(wrong, np.nan, screen_out[k])
    return wrong
