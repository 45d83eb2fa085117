"""Angle offset: the actuator is not straight at zero pressure, or the angle's zero is off."""

from __future__ import annotations

from surrogate.calibration.effects._base import Effect, EffectParameter


class AngleOffset(Effect):
    id = "angle_offset"
    title = "Angle offset"
    measure_directly = "read the angle of the unpressurised actuator before each run"
    stage = "angle"
    kind = "measurement"
    parameters = (EffectParameter(
        "offset_deg", "deg", 0.0, (-30.0, 30.0), (-8.0, 8.0), 0.0,
        "angle at zero pressure: pre-curvature from bonding, gravity sag, or the zero "
        "of the angle reading"),)
    description = "observed angle = angle + offset at every pressure."

    def observed(self, angle_deg, values):
        return angle_deg + values["offset_deg"]

    def interpret(self, params, data):
        v = params["offset_deg"]
        return (f"The actuator rests at {v['value']:.1f} +/- {v['sd']:.1f} deg at zero "
                "pressure (pre-curvature or sag): zero the angle on the unpressurised "
                "actuator.")


EFFECT = AngleOffset()
