"""Hydraulic resistance of the inlet channel and tubing: the gauge reads R Q above the
chamber while fluid flows in, R Q below while it is withdrawn, and the chamber during a
hold (Hagen-Poiseuille, laminar)."""

from __future__ import annotations

import math

from surrogate.calibration.effects._base import Effect, EffectParameter

WATER_VISCOSITY_PA_S = 1.0e-3  # 20 degC

# The paper's inlet: a straight channel 0.5 mm x 3 mm (width x length), 150 um high
# (soft lithography, SU-8 150 um); tubing is not described, 0.5 mm bore assumed.
CHANNEL_WIDTH_MM = 0.5
CHANNEL_LENGTH_MM = 3.0
CHANNEL_HEIGHT_MM = 0.15
TUBING_BORE_MM = 0.5
TUBING_LENGTH_MM = 1000.0


def rectangular_channel_resistance_pa_per_ul_s(length_mm: float, width_mm: float,
                                               height_mm: float,
                                               viscosity_pa_s: float = WATER_VISCOSITY_PA_S
                                               ) -> float:
    """Hagen-Poiseuille resistance of a shallow rectangular channel (h < w),
    R = 12 mu L / (w h^3 (1 - 0.63 h/w)), in Pa per ul/s (1 ul/s = 1e-9 m^3/s)."""
    L, w, h = length_mm * 1e-3, width_mm * 1e-3, height_mm * 1e-3
    h, w = min(h, w), max(h, w)
    r_si = 12.0 * viscosity_pa_s * L / (w * h**3 * (1.0 - 0.63 * h / w))
    return r_si * 1e-9


def round_tube_resistance_pa_per_ul_s(length_mm: float, bore_mm: float,
                                      viscosity_pa_s: float = WATER_VISCOSITY_PA_S) -> float:
    """Hagen-Poiseuille resistance of a round tube, R = 8 mu L / (pi r^4), Pa per ul/s."""
    r = 0.5 * bore_mm * 1e-3
    return 8.0 * viscosity_pa_s * length_mm * 1e-3 / (math.pi * r**4) * 1e-9


R_CHANNEL = rectangular_channel_resistance_pa_per_ul_s(CHANNEL_LENGTH_MM, CHANNEL_WIDTH_MM,
                                                       CHANNEL_HEIGHT_MM)
R_TUBING_1M = round_tube_resistance_pa_per_ul_s(TUBING_LENGTH_MM, TUBING_BORE_MM)


class HydraulicResistance(Effect):
    id = "hydraulic_resistance"
    title = "Inlet channel and tubing resistance"
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
        if data.n_flow_rates < 2 and not data.has_unloading and not data.has_holds:
            return ("one flow rate, loading only: exactly a pressure offset p0 = R Q",
                    "measure at a second flow rate, or record a hold or the unloading")
        return None

    def chamber_pressure(self, p_pa, flow_ul_s, direction, values):
        return p_pa - values["R_pa_per_ul_s"] * flow_ul_s * direction

    def interpret(self, params, data):
        v = params["R_pa_per_ul_s"]
        q = max(data.get("flow_rates_ul_s") or [2.5])
        return (f"Inlet channel and tubing resistance {v['value']:.0f} +/- {v['sd']:.0f} Pa "
                f"per ul/s: while pumping at {q:g} ul/s the gauge reads about "
                f"{v['value'] * q:.0f} Pa above the chamber (the 0.5 x 3 mm x 150 um channel "
                f"alone accounts for about {R_CHANNEL:.0f} Pa per ul/s; the rest is tubing "
                "and connectors). Measure pressure at the chip or correct it.")


EFFECT = HydraulicResistance()
