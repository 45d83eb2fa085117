"""Pressure offset: the gauge's zero is off (or it sits above the chip)."""

from __future__ import annotations

from surrogate.calibration.effects._base import Effect, EffectParameter


class PressureOffset(Effect):
    id = "pressure_offset"
    title = "Pressure offset"
    measure_directly = "read the gauge open to the atmosphere (its zero) before each run"
    stage = "pressure"
    kind = "measurement"
    parameters = (EffectParameter(
        "p0_pa", "Pa", 0.0, (-1000.0, 1000.0), (-300.0, 300.0), 0.0,
        "gauge reading minus chamber pressure at any flow: zero error of the sensor, or "
        "its height above the chip (10 mm of water = 98 Pa)"),)
    description = ("p_chamber = p_gauge - p0. Identified by the bend it removes or adds at "
                   "low pressure, and by shifting every design's curve alike.")

    def chamber_pressure(self, p_pa, flow_ul_s, direction, values):
        return p_pa - values["p0_pa"]

    def gauge_pressure(self, p_pa, flow_ul_s, direction, values):
        return p_pa + values["p0_pa"]

    def interpret(self, params, data):
        v = params["p0_pa"]
        return (f"The gauge reads {v['value']:.0f} +/- {v['sd']:.0f} Pa above the chamber at "
                "every flow (sensor zero, or the sensor's height above the chip: 98 Pa per "
                "10 mm of water): zero the sensor with the actuator open to air.")


EFFECT = PressureOffset()
