"""Hydraulic resistance of the inlet channel and tubing: the gauge reads R Q above the
chamber while fluid flows in, R Q below while it is withdrawn, and the chamber during a
hold (Hagen-Poiseuille, laminar: surrogate/hydraulics.py)."""

from __future__ import annotations

from surrogate.calibration.effects._base import Effect, EffectParameter
from surrogate.hydraulics import (
    CHANNEL_HEIGHT_MM,
    CHANNEL_LENGTH_MM,
    CHANNEL_WIDTH_MM,
    rectangular_channel_resistance_pa_per_ul_s,
    round_tube_resistance_pa_per_ul_s,
)

# Tubing is not described in the paper: 0.5 mm bore, 1 m assumed for the plausible range.
TUBING_BORE_MM = 0.5
TUBING_LENGTH_MM = 1000.0


R_CHANNEL = rectangular_channel_resistance_pa_per_ul_s(CHANNEL_LENGTH_MM, CHANNEL_WIDTH_MM,
                                                       CHANNEL_HEIGHT_MM)
R_TUBING_1M = round_tube_resistance_pa_per_ul_s(TUBING_LENGTH_MM, TUBING_BORE_MM)


class HydraulicResistance(Effect):
    id = "hydraulic_resistance"
    title = "Inlet channel and tubing resistance"
    measure_directly = ("read the pressure at the chip as well as at the pump, or repeat at "
                        "a second flow rate")
    stage = "pressure"
    kind = "measurement"
    needs = ("flow_ul_s",)
    parameters = (EffectParameter(
        "R_pa_per_ul_s", "Pa per ul/s", 0.0, (0.0, 5000.0),
        (round(0.5 * R_CHANNEL, 1), round(R_CHANNEL + R_TUBING_1M, 1)), 50.0,
        "pressure drop per flow rate between the gauge and the chamber; the paper's inlet "
        f"channel alone (water, 0.5 x 3 mm, 150 um high) gives {R_CHANNEL:.0f}, 1 m of "
        f"0.5 mm bore tubing adds {R_TUBING_1M:.0f}"),)
    description = ("p_chamber = p_gauge - R Q d, d = +1 while pumping in, -1 while "
                   "withdrawing, 0 during a hold. At one flow rate without holds or "
                   "unloading it is exactly a pressure offset p0 = R Q.")

    def not_identifiable(self, data):
        if not data.has_flow:
            return ("needs the flow rate of each curve", "record flow_ul_s")
        if not data.pump_varies:
            return ("one flow rate, loading only: exactly a pressure offset p0 = R Q",
                    "measure at a second flow rate, or record a hold or the unloading")
        return None

    def chamber_pressure(self, p_pa, flow_ul_s, direction, values):
        return p_pa - values["R_pa_per_ul_s"] * flow_ul_s * direction

    def gauge_pressure(self, p_pa, flow_ul_s, direction, values):
        return p_pa + values["R_pa_per_ul_s"] * flow_ul_s * direction

    def interpret(self, params, data):
        v = params["R_pa_per_ul_s"]
        q = max(data.get("flow_rates_ul_s") or [2.5])
        return (f"Inlet channel and tubing resistance {v['value']:.3g} +/- {v['sd']:.2g} Pa "
                f"per ul/s: while pumping at {q:g} ul/s the gauge reads about "
                f"{v['value'] * q:.0f} Pa above the chamber (the 0.5 x 3 mm x 150 um channel "
                f"alone accounts for about {R_CHANNEL:.0f} Pa per ul/s; the rest is tubing "
                "and connectors). Measure pressure at the chip or correct it.")


EFFECT = HydraulicResistance()
