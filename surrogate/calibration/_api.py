"""One call for the CLI and the HTTP layer: rows or a file -> Calibration."""

from __future__ import annotations

import math
import threading
from typing import Any

from surrogate.calibration._data import Observations, observations_from_rows
from surrogate.calibration._loop import Calibration, calibrate
from surrogate.calibration._start import baseline_for


def run_calibration(data: Observations | list[dict[str, Any]], model: Any = None,
                    folds: int = 5, progress=None, strict: bool = False,
                    cancel: threading.Event | None = None) -> Calibration:
    """Validate ``data`` (rows or Observations) and run the loop against ``model``: None
    or "paper" (the paper's constants), or any ``surrogate.predictor.Predictor``.
    ``cancel``: set by another thread, the loop stops at its next fit or
    cross-validation with ``surrogate.errors.Cancelled``."""
    obs = data if isinstance(data, Observations) else observations_from_rows(data, strict)
    cal = calibrate(obs, baseline_for(model), folds=folds, progress=progress, cancel=cancel)
    cal.report["saveable"] = save_status(cal)
    return cal


def save_status(cal: Calibration) -> dict[str, Any]:
    """Whether ``save_model`` would keep this calibration, and why not in its own words
    (``saveable``): in every report, so that a page or a script knows before it asks."""
    from solver.errors import InputError

    try:
        saveable(cal)
    except InputError as exc:
        return {"ok": False, "why": exc.detail}
    return {"ok": True, "why": None}


# Effects a saved model (_saved.py: the exponential model's quasi-static form) carries.
SAVEABLE_EFFECTS = ("pressure_offset", "hydraulic_resistance", "angle_offset",
                    "membrane_thickness", "viscoelastic_creep")


def saveable(cal: Calibration) -> None:
    """Raise InputError (field ``save``) when the saved-model format cannot hold this
    calibration: against a per-family baseline it stores the exponential constants and
    the SAVEABLE_EFFECTS; against a design-space baseline (the emulator) any selection
    (``_saved_design.py``: the physical effects applied, the others recorded)."""
    from solver.errors import InputError

    r = cal.report
    after = r["rmse_after_deg"]
    if after is None or not math.isfinite(after):
        raise InputError("save", "the calibration has no cross-validated error (held-out "
                         "curves reach past the end of the baseline's range): nothing to "
                         "save", "a calibration with a finite cross-validated error (against "
                         "the emulator, the default)")
    left = [what for what, bad in (
        ("the angle", r["residual_structured_after"]),
        ("the gauge pressure", (r.get("gauge_left_after") or {}).get("left", False))) if bad]
    if left:
        # saved, its answers would carry bands that miss the lab's actuators (20 deg at
        # 2000 Pa: an unexplained gauge misfit of 24x its floor, 2026-12-06)
        raise InputError("save", f"the calibration leaves structure in {' and '.join(left)} "
                         "that its selected effects do not explain: a saved model would not "
                         "stand for your actuators (the report and its interpretation say "
                         "what is left and what to measure)",
                         "a calibration that leaves only replicate scatter")
    if "families" not in r["fitted"]:
        return      # a design-space baseline: every effect is saved (_saved_design.py)
    other = [e for e in cal.report["selected_effects"] if e not in SAVEABLE_EFFECTS]
    if other:
        raise InputError("save", f"effect {other[0]} cannot be saved in a calibrated model "
                         "yet", "calibrations selecting only " + ", ".join(SAVEABLE_EFFECTS))
