"""The one interface every model implements: emulator, exponential, paper, calibrated.

Routes, CLI commands and the calibration loop call only these methods, so they never
branch on a model's kind:

    p = model.predict(design, pressures_pa, level=0.95)   -> Prediction
    q = model.inverse(design, angles_deg, level=0.95)     -> InversePrediction

Contract (what every implementation guarantees):
- angles in degrees (signed: negative when the actuator bends towards the membrane,
  as the reversed pair does), pressures in Pa (chamber pressure), force in mN;
- ``lower_deg``/``upper_deg`` a band at ``level`` (two-sided, for a new FE solve of the
  design, not only the model's mean);
- no number the physics does not support: a pressure past the end of the FE's
  converged, stable range for the design gets angle NaN (null over HTTP), and the
  prediction's ``validity`` says so (flag ``past_fe_range``, ``fe_limit_pa`` and why
  the FE stopped);
- a design the model cannot answer for raises ``InputError`` naming the field and the
  allowed range (``OutOfFamilyError`` / ``OutOfBoxError`` carry the nearest design).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from solver.design import Design
from surrogate.core import InversePrediction, Prediction


@runtime_checkable
class Predictor(Protocol):
    """A model that answers angle(pressure) and pressure(angle) for a design."""

    name: str

    def predict(self, design: Design, pressures_pa: object, level: float = 0.95
                ) -> Prediction:
        """Angle (deg) at each pressure (Pa >= 0), with a band at ``level``."""
        ...

    def inverse(self, design: Design, angle_deg: object, level: float = 0.95
                ) -> InversePrediction:
        """Chamber pressure (Pa) giving each angle (deg), with a band at ``level``."""
        ...
