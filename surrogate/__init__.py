"""Surrogate layer: the models fitted from the FE curve database, with prediction bands,
validity flags and inverse design -- the design-space emulator (the default,
``surrogate.emulator``), the paper's exponential model (``surrogate.exponential``, named
``exponential``; its published constants as ``paper``) and the calibration loop against
measured data (``surrogate.calibration``); every model implements
``surrogate.predictor.Predictor``. This package's top level re-exports the exponential
model's names:

    from surrogate import paper_surrogate, load_surrogate, fit_surrogate, inverse_design
    s = paper_surrogate()                        # the paper's constants, name "paper"
    s.predict(design, [0, 1000, 2000])           # Prediction: angle_deg, lower/upper_deg
    s.inverse(design, 45.0)                      # InversePrediction: pressure_pa + band
    s = fit_surrogate("curves.h5"); save_surrogate(s, "surrogate.json")

Model (docs/surrogate.md): angle_deg = A (exp(p/tau) - 1), A = a L,
tau = a_t log10(b_t t); the "extended" form adds c: exp(x + c x^2), x = p / tau.
Errors: OutOfFamilyError and SurrogateFileError (both InputError, see surrogate.errors).
"""

from surrogate.dataset import CurveData, curves_from_store
from surrogate.errors import OutOfFamilyError, SurrogateFileError
from surrogate.exponential.file import (
    FORMAT_VERSION,
    load_surrogate,
    open_surrogate,
    save_surrogate,
)
from surrogate.exponential.fit_from_curves import fit_surrogate
from surrogate.exponential.inverse_design import DesignBounds, inverse_design
from surrogate.exponential.paper_preset import paper_surrogate
from surrogate.exponential.surrogate import Surrogate
from surrogate.predictor import InversePrediction, Prediction, Predictor
from surrogate.search.design_result import DesignCandidate, InverseDesignResult
from surrogate.search.design_target import DesignTarget

__all__ = [
    "FORMAT_VERSION", "CurveData", "DesignBounds", "DesignCandidate", "DesignTarget",
    "InverseDesignResult", "InversePrediction", "OutOfFamilyError", "Prediction", "Predictor",
    "Surrogate",
    "SurrogateFileError", "curves_from_store", "fit_surrogate", "inverse_design",
    "load_surrogate", "open_surrogate", "paper_surrogate", "save_surrogate",
]
