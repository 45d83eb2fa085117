"""The baseline of a calibration: a Predictor, and what it leaves open.

``baseline_for(model)``: ``model`` is None or "paper" (the paper's constants), or any
object implementing ``surrogate.predictor.Predictor`` (the design-space emulator, a fitted
exponential surrogate, a saved model). The loop calls only ``predict``.

What the baseline leaves open is what the recalibrated baseline frees:

* a model with per-family constants (it answers ``family_parameters``: the exponential
  and paper models) leaves them open: per family an amplitude scale (its a) and a
  pressure scale (its a_t); the thickness law (b_t) stays. Camera gain and pressure gain
  are then exactly these and are not fitted.
* a design-space model (the emulator) leaves nothing open: every input is the design, and
  what differs in a lab's actuators (stiffness, thickness, length) is an effect acting
  through those inputs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

OPEN_EXPONENTIAL = ("amplitude", "pressure_scale")


@dataclass(frozen=True)
class Baseline:
    predictor: Any
    name: str
    open_parameters: tuple[str, ...]
    why: str

    def as_dict(self) -> dict[str, object]:
        return {"name": self.name, "open_parameters": list(self.open_parameters),
                "why": self.why}


def baseline_for(model: Any = None) -> Baseline:
    if model is None or model == "paper":
        from surrogate import paper_surrogate

        model = paper_surrogate()
    name = str(getattr(model, "name", type(model).__name__))
    if callable(getattr(model, "family_parameters", None)):
        return Baseline(model, name, OPEN_EXPONENTIAL,
                        "a per-family model: its constants are fitted to each family's data "
                        "by construction, so the recalibration frees per family the "
                        "amplitude (a) and the pressure scale (a_t); b_t (thickness law) "
                        "stays")
    return Baseline(model, name, (), "a design-space model: every input is the design "
                    "(materials, L, t, ...), so nothing is left open; what differs in the "
                    "lab's actuators is an effect acting through those inputs")
