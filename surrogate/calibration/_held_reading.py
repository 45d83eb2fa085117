"""The falling readings read a second way: as a hold in which the bend falls, not as the
pump withdrawing, when the data carry no pump log and the history was read off them.

Without the pump's log (the `pump` column) the history comes from the readings
(_history.py): a bend and a gauge that fall read as unloading. A hold in which a leak lets
the chamber empty falls too, so a leak in a hold reads as unloading, and creep then stands
in for the leak (benchmarks/lab_rig_sets.py L6: a leak of 0.2 ul/s per kPa in a 6 s hold,
read as creep g 0.234 +/- 0.012, cross-validated 2.14 deg). The two readings of one data
set are two models of the same readings, so the data can choose: the loop is run again
with every reading read as unloading read as a hold instead, and that reading is kept
only where it explains the data better -- something selected, no structure left, and a
lower cross-validated error of the angle and of both channels together than the first
reading's. On L6 it is (chamber_leak 0.221 +/- 0.025, 1.93 against 2.14 deg; 1.68 against
1.80 both channels); on the lab sets whose pump did withdraw (L2, L7, N1) the hold reading
leaves 10-16 deg flagged, and the unloading stays.

It is asked only where the first reading's selection holds a time effect (creep,
relaxation, a leak or a drift: what a misread hold is taken up by) or leaves structure,
with time_s and flow_ul_s, and no measured volume (which places the readings itself). The
report's `history_read_as_hold` gives both readings' selections and errors, and which was
taken; the interpretation says so and asks for the pump's log to confirm.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from surrogate.calibration._data import Observations
from surrogate.calibration.effects import EFFECTS


def wants_held_reading(report: dict) -> bool:
    """Whether the falling readings are read a second way (see the module's docstring)."""
    data = report["data"]
    timed = any(EFFECTS[e].stage == "time" for e in report["selected_effects"])
    return (not data.get("pump_logged") and data["has_time_s"] and data["has_flow_ul_s"]
            and data["injected_volume"] == "pump history"
            and data["readings"]["unloading"] > 0
            and (timed or bool(report["residual_structured_after"])))


def held_instead(obs: Observations) -> Observations:
    """``obs`` with every reading read as unloading read as a hold: the injected volume
    and the pump's switches follow from that history (Observations.__post_init__)."""
    return replace(obs, direction=np.where(obs.direction < 0, 0, obs.direction),
                   volume_ul=None, volume_measured=None, switch_after=None, switch_at=None,
                   switch_names=())


def summary(report: dict) -> dict:
    """One reading's selection: effects, sizes, errors (angle, gauge, both channels)."""
    chosen = report["selected_effects"]
    joint = next((c["rmse_cv_joint"] for c in report["candidates"]
                  if c["effects"] == chosen), None) if chosen else None
    return {"readings": dict(report["data"]["readings"]), "selected_effects": list(chosen),
            "params": {n: {"value": p["value"], "sd": p["sd"], "unit": p["unit"]}
                       for n, p in report["fitted"]["effects"].items()},
            "rmse_after_deg": report["rmse_after_deg"],
            "rmse_pressure_after_pa": report["rmse_pressure_after_pa"],
            "rmse_cv_joint": joint, "structured": bool(report["residual_structured_after"])}


def reads_better(held: dict, unloading: dict) -> bool:
    """The hold reading explains the data better: something selected, no structure, and
    lower cross-validated errors, the angle's and both channels' (``summary`` dicts)."""
    if not held["selected_effects"] or held["structured"] or held["rmse_cv_joint"] is None:
        return False
    angle_lower = held["rmse_after_deg"] < unloading["rmse_after_deg"]
    joint = unloading["rmse_cv_joint"]
    return bool(angle_lower and (joint is None or held["rmse_cv_joint"] < joint))


def sentence(read: dict | None) -> str | None:
    """What the interpretation says of the two readings (None when not asked)."""
    if read is None:
        return None
    held, unl = read["hold"], read["unloading"]
    n = unl["readings"]["unloading"]

    def said(s: dict) -> str:
        sel = " and ".join(s["selected_effects"]) or "nothing"
        return (f"{sel} (cross-validated {s['rmse_after_deg']:.2f} deg"
                + (", left structured" if s["structured"] else "") + ")")
    if read["taken"]:
        return (f"The pump's history was read off the readings, and its {n} falling "
                f"readings read two ways: as the pump withdrawing they give {said(unl)}; "
                f"as a hold in which the bend falls (the pump stopped, a leak) "
                f"{said(held)}, which explains the data better and is the reading taken. "
                "Give the pump's log (the pump column: load, hold or unload before each "
                "reading, docs/measured-data.md) to confirm it.")
    return (f"Read as a hold instead of the pump withdrawing, the {n} falling readings give "
            f"{said(held)}: the data chose the unloading.")
