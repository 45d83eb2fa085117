"""Pressure gain: the sensor reads k times the chamber pressure (calibration of the gauge).

A batch of specimens uniformly k times as stiff makes the same readings exactly: the Ogden
energy is linear in its moduli, so a solid whose every mu is x k takes the same shape at
the same injected volume at k times the pressure (docs/calibration.md, "Two
observables", the table's last row). The gain is named with that batch beside it.
"""

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
    exactly_as = ("membrane_stiffness", "body_stiffness")
    exactly_as_why = ("a gauge reading k x the chamber pressure and a batch of specimens "
                      "uniformly k x as stiff (both layers' Ogden mu x k: the same shape at "
                      "the same volume at k x the pressure) make the same readings of bend "
                      "and gauge")

    def chamber_pressure(self, p_pa, flow_ul_s, direction, values):
        return p_pa / values["k_pressure"]

    def gauge_pressure(self, p_pa, flow_ul_s, direction, values):
        return p_pa * values["k_pressure"]

    def exactly_as_params(self, params):
        k = params["k_pressure"]
        return {name: {"value": k["value"], "sd": k["sd"], "unit": "-"}
                for name in ("membrane_mu_scale", "body_mu_scale")}

    def interpret(self, params, data):
        v = params["k_pressure"]
        pct, sd = 100 * (v["value"] - 1), 100 * v["sd"]
        return (f"The gauge reads {abs(pct):.1f} +/- {sd:.1f} % {'low' if pct < 0 else 'high'} "
                "against the pressure the nominal actuator would have: the sensor's span "
                f"error or, the same readings exactly, a batch of specimens uniformly "
                f"{abs(pct):.1f} +/- {sd:.1f} % {'softer' if pct < 0 else 'stiffer'} than "
                "their presets (both layers).")


EFFECT = PressureGain()
