"""Closing the loop with measured data: residual -> missing effect -> augmented model.

    obs = load_observations("data.csv")              # or observations_from_rows(rows)
    cal = run_calibration(obs, model="paper")        # or a surrogate object
    cal.report                                       # the JSON report (docs/calibration.md)
    plot_calibration(cal, "report.png")
    save_model(cal, "lab1", models_dir); load_model("lab1", models_dir).predict(design, p)

Errors: DataError (an InputError naming row and column), ModelNotFoundError (a
NotFoundError).
"""

from surrogate.calibration._api import jsonable, run_calibration
from surrogate.calibration._baseline import PAPER_PARAMETERS, FamilyParameters
from surrogate.calibration._data import (
    OPTIONAL,
    REQUIRED,
    Observations,
    load_observations,
    observations_from_rows,
    read_csv_rows,
)
from surrogate.calibration._effects import (
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
from surrogate.calibration._errors import DataError, ModelNotFoundError
from surrogate.calibration._loop import Calibration, calibrate
from surrogate.calibration._plot import plot_calibration
from surrogate.calibration._saved import (
    CalibratedModel,
    CalibratedPrediction,
    load_model,
    save_model,
)
from surrogate.calibration._start import starting_parameters

__all__ = [
    "CATALOGUE", "EFFECTS", "EFFECT_IDS", "OPTIONAL", "PAPER_PARAMETERS", "REQUIRED",
    "R_CHANNEL", "CalibratedModel", "CalibratedPrediction", "Calibration", "DataError",
    "Effect", "EffectParameter", "FamilyParameters", "ModelNotFoundError", "Observations",
    "calibrate", "catalogue_dicts", "jsonable", "load_model", "load_observations",
    "observations_from_rows", "plot_calibration", "read_csv_rows",
    "rectangular_channel_resistance_pa_per_ul_s", "round_tube_resistance_pa_per_ul_s",
    "run_calibration", "save_model", "starting_parameters",
]
