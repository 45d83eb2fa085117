"""Closing the loop with measured data: residual -> missing effect -> augmented model.

    obs = load_observations("data.csv")              # or observations_from_rows(rows)
    cal = run_calibration(obs, model)                # any Predictor, or "paper"
    cal.report                                       # the JSON report (docs/calibration.md)
    plot_calibration(cal, "report.png")

The effects are objects, one file each, in ``surrogate.calibration.effects``.
Errors: DataError (an InputError naming row and column), ModelNotFoundError (a
NotFoundError).
"""

from surrogate.calibration._api import run_calibration, saveable
from surrogate.calibration._baseline import PAPER_PARAMETERS, FamilyParameters
from surrogate.calibration._data import (
    OPTIONAL,
    REQUIRED,
    Observations,
    decode_text,
    load_observations,
    observations_from_rows,
    read_csv_rows,
)
from surrogate.calibration._errors import DataError, ModelNotFoundError
from surrogate.calibration._loop import Calibration, calibrate
from surrogate.calibration._plot import plot_calibration
from surrogate.calibration._saved import (
    CalibratedModel,
    CalibratedPrediction,
    load_model,
    save_model,
)
from surrogate.calibration._start import Baseline, baseline_for
from surrogate.calibration.effects import (
    CATALOGUE,
    EFFECT_IDS,
    EFFECTS,
    R_CHANNEL,
    Effect,
    EffectParameter,
    catalogue_dicts,
    rectangular_channel_resistance_pa_per_ul_s,
    round_tube_resistance_pa_per_ul_s,
)
from surrogate.json_plain import plain_json as jsonable  # the report as plain JSON

__all__ = [
    "CATALOGUE", "EFFECTS", "EFFECT_IDS", "OPTIONAL", "PAPER_PARAMETERS", "REQUIRED",
    "R_CHANNEL", "Baseline", "CalibratedModel", "CalibratedPrediction", "Calibration",
    "DataError", "Effect", "EffectParameter", "FamilyParameters", "ModelNotFoundError",
    "Observations", "baseline_for", "calibrate", "catalogue_dicts", "decode_text",
    "jsonable", "load_model", "load_observations", "observations_from_rows",
    "plot_calibration", "read_csv_rows", "rectangular_channel_resistance_pa_per_ul_s",
    "round_tube_resistance_pa_per_ul_s", "run_calibration", "save_model", "saveable",
]
