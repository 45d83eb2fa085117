"""Membrane thickness: the spin-coated membrane is thinner or thicker than nominal."""

from __future__ import annotations

from dataclasses import replace

from surrogate.calibration.effects._base import Effect, EffectParameter


class MembraneThickness(Effect):
    id = "membrane_thickness"
    title = "Membrane thickness change"
    measure_directly = "measure the membrane thickness on a cut specimen"
    stage = "design"
    kind = "physical"
    parameters = (EffectParameter(
        "dt_mm", "mm", 0.0, (-0.2, 0.2), (-0.15, 0.15), 0.0,
        "fabricated minus nominal membrane thickness (spin speed, time, viscosity)"),)
    description = "t -> t + dt in the design the baseline answers for (through the FE)."

    def design(self, design, value):
        return replace(design, t_mm=design.t_mm + value)

    def interpret(self, params, data):
        v = params["dt_mm"]
        return (f"The membranes are {1000 * v['value']:+.0f} +/- {1000 * v['sd']:.0f} um "
                "thicker than nominal: measure the spin-coated thickness (profilometer, or "
                "a cross-section under the microscope).")


EFFECT = MembraneThickness()
