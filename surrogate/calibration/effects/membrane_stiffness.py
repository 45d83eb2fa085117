"""Membrane stiffness: the membrane's silicone is stiffer or softer than its preset."""

from __future__ import annotations

from dataclasses import replace

from surrogate.calibration.effects._base import Effect, EffectParameter
from surrogate.calibration.effects._materials import scale_layer


class MembraneStiffness(Effect):
    id = "membrane_stiffness"
    title = "Membrane stiffness scale"
    measure_directly = "tensile-test the membrane material (its Ogden mu)"
    stage = "design"
    kind = "physical"
    parameters = (EffectParameter(
        "membrane_mu_scale", "-", 1.0, (0.5, 2.0), (0.6, 1.6), 1.0,
        "measured over nominal shear moduli of the membrane layer (mixing ratio, cure, "
        "age)"),)
    description = ("The membrane's Ogden mu_p x s in the design the baseline answers for: "
                   "through the FE (emulator) it moves both the pressure scale and the "
                   "amplitude of the curve.")

    def design(self, design, value):
        return replace(design, membrane_material=scale_layer(design.membrane_material,
                                                                 value))

    def interpret(self, params, data):
        v = params["membrane_mu_scale"]
        return (f"The membrane behaves {100 * (v['value'] - 1):+.0f} +/- "
                f"{100 * v['sd']:.0f} % stiff relative to its preset: check its mixing "
                "ratio and cure, or measure its modulus (uniaxial test).")


EFFECT = MembraneStiffness()
