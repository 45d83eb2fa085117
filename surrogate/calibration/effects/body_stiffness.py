"""Body stiffness: the body's silicone is stiffer or softer than its preset."""

from __future__ import annotations

from dataclasses import replace

from surrogate.calibration.effects._base import Effect, EffectParameter
from surrogate.calibration.effects._materials import scale_layer


class BodyStiffness(Effect):
    id = "body_stiffness"
    title = "Body stiffness scale"
    measure_directly = "tensile-test the body material (its Ogden mu)"
    stage = "design"
    kind = "physical"
    parameters = (EffectParameter(
        "body_mu_scale", "-", 1.0, (0.5, 2.0), (0.6, 1.8), 1.0,
        "measured over nominal shear moduli of the body layer (PDMS mixing ratio, cure "
        "temperature and time)"),)
    description = ("The body's Ogden mu_p x s in the design the baseline answers for: "
                   "mostly the pressure scale of the bend, through the FE.")

    def design(self, design, value):
        return replace(design, body_material=scale_layer(design.body_material, value))

    def interpret(self, params, data):
        v = params["body_mu_scale"]
        return (f"The body behaves {100 * (v['value'] - 1):+.0f} +/- {100 * v['sd']:.0f} % "
                "stiff relative to its preset: check the PDMS mixing ratio and cure.")


EFFECT = BodyStiffness()
