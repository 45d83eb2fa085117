"""Chamber length: the moulded (or bonded) chamber is longer or shorter than nominal."""

from __future__ import annotations

from dataclasses import replace

from surrogate.calibration.effects._base import Effect, EffectParameter


class ChamberLength(Effect):
    id = "chamber_length"
    title = "Chamber length change"
    measure_directly = "measure the chamber length on the mould or a cut specimen"
    stage = "design"
    kind = "physical"
    parameters = (EffectParameter(
        "dL_mm", "mm", 0.0, (-2.0, 2.0), (-1.0, 1.0), 0.0,
        "effective minus nominal chamber length (mould tolerance, unbonded rim at the "
        "chamber's ends, shrinkage)"),)
    description = "L -> L + dL in the design the baseline answers for (through the FE)."

    def design(self, design, value):
        return replace(design, L_mm=design.L_mm + value)

    def interpret(self, params, data):
        v = params["dL_mm"]
        return (f"The chambers act {v['value']:+.2f} +/- {v['sd']:.2f} mm longer than "
                "nominal (mould, or a rim left unbonded at the chamber's ends): measure "
                "the chamber under the microscope.")


EFFECT = ChamberLength()
