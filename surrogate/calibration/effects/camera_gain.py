"""Camera gain: angles read from images are scaled (perspective, tilted camera, wrong
reference line)."""

from __future__ import annotations

from surrogate.calibration.effects._base import Effect, EffectParameter


class CameraGain(Effect):
    id = "camera_gain"
    title = "Camera (angle reading) gain"
    measure_directly = "read a target of known angle (a protractor card) in the camera's view"
    stage = "angle"
    kind = "measurement"
    parameters = (EffectParameter(
        "k_angle", "-", 1.0, (0.5, 2.0), (0.85, 1.15), 1.0,
        "read angle over true angle: a camera not perpendicular to the bending plane "
        "reads tan(angle) x cos(tilt)"),)
    description = "observed angle = k x angle: every curve scaled in angle alike."
    same_as_open = ("amplitude",)

    def observed(self, angle_deg, values):
        return angle_deg * values["k_angle"]

    def interpret(self, params, data):
        v = params["k_angle"]
        return (f"Angles are read {100 * (v['value'] - 1):+.1f} +/- {100 * v['sd']:.1f} % "
                "off scale (camera tilted out of the bending plane, or perspective): "
                "check the angle reading against a protractor target.")


EFFECT = CameraGain()
