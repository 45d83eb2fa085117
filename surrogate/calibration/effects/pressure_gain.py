"""Pressure gain: the sensor reads k times the chamber pressure (calibration of the gauge)."""

from __future__ import annotations

from surrogate.calibration.effects._base import Effect, EffectParameter


class PressureGain(Effect):
    id = "pressure_gain"
    title = "Pressure sensor gain"
    measure_directly = "check the gauge against a reference gauge at two pressures"
    stage = "pressure"
    kind = "measurement"
    parameters = (EffectParameter(
        "k_pressure", "-", 1.0, (0.5, 2.0), (0.85, 1.15), 1.0,
        "gauge reading over true pressure (sensor span error, wrong unit factor "
        "within a few %)"),)
    description = "p_chamber = p_gauge / k: every curve stretched along pressure alike."
    same_as_open = ("pressure_scale",)

    def chamber_pressure(self, p_pa, flow_ul_s, direction, values):
        return p_pa / values["k_pressure"]

    def gauge_pressure(self, p_pa, flow_ul_s, direction, values):
        return p_pa * values["k_pressure"]

    def interpret(self, params, data):
        v = params["k_pressure"]
        return (f"The pressure sensor reads {100 * (v['value'] - 1):+.1f} +/- "
                f"{100 * v['sd']:.1f} % of the true pressure (span error): calibrate it "
                "against a water column.")


EFFECT = PressureGain()
