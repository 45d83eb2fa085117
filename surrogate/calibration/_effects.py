"""The catalogue of candidate effects: what the baseline exponential model may miss.

Each effect is a small named term with physical parameters (units, hard bounds for the
fit, the range that is physically plausible for this device, and the value at which the
effect vanishes), the data columns it needs, and the stage of the model it acts on:

    p_chamber = p_gauge - p0 - R Q                      pressure_offset, hydraulic_resistance
    tau       = s a_t log10(b_t (t + dt))               stiffness_scale, membrane_thickness_bias
    forward   = theta_max tanh(A (e^(p/tau) - 1) / theta_max)          saturation
    static    = forward - d (p/p_r) exp(1 - p/p_r)                    reverse_bending
    angle     = lag(static; tau_v) + c0                 viscoelastic_lag, angle_offset

"structural" effects add a shape the baseline cannot make and are fitted together with the
freely recalibrated baseline. "parameter" effects act only through tau, which the
recalibrated baseline already moves freely (stiffness_scale is exactly a change of a_t;
a thickness bias is a change of b_t up to a small curvature in log t), so they are fitted
with the family's tau law pinned at the starting model's a_t, b_t: they are tested as a
physical, fewer-parameter explanation of the recalibration. See docs/calibration.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

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


@dataclass(frozen=True)
class EffectParameter:
    """One physical parameter. ``fit_bounds`` are hard limits of the optimiser;
    ``plausible`` is the range expected for this device; ``null`` switches the effect off.
    ``internal`` names a reparametrisation used in the fit (saturation fits 1/theta_max)."""

    name: str
    unit: str
    null: float
    fit_bounds: tuple[float, float]
    plausible: tuple[float, float]
    start: float
    description: str
    tested: bool = True  # False: a shape parameter, undefined when the effect is off


@dataclass(frozen=True)
class Effect:
    id: str
    title: str
    kind: str  # "structural" | "parameter"
    needs: tuple[str, ...]
    parameters: tuple[EffectParameter, ...]
    description: str

    def as_dict(self) -> dict[str, object]:
        return {
            "id": self.id, "title": self.title, "kind": self.kind, "needs": list(self.needs),
            "description": self.description,
            "parameters": [{"name": p.name, "unit": p.unit, "null": _finite(p.null),
                            "bounds": [_finite(b) for b in p.fit_bounds],
                            "plausible": list(p.plausible), "description": p.description}
                           for p in self.parameters]}


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


BASE_COLUMNS = ("pressure_pa", "angle_deg", "L_mm", "t_mm")

CATALOGUE: tuple[Effect, ...] = (
    Effect("pressure_offset", "Pressure offset", "structural", BASE_COLUMNS,
           (EffectParameter("p0_pa", "Pa", 0.0, (-1000.0, 1000.0), (-300.0, 400.0), 0.0,
                            "gauge reading minus chamber pressure at any flow: a gauge zero "
                            "error, or the transition pressure below which the membrane does "
                            "not yet drive the bend (up to ~350 Pa in FE runs)"),),
           "Chamber pressure = gauge pressure - p0. With the free baseline it is identified "
           "by the angle it removes at low pressure and by A_eff = A exp(-p0/tau) changing "
           "with thickness; with a single thickness it is nearly a change of a."),
    Effect("hydraulic_resistance", "Inlet channel and tubing resistance", "structural",
           BASE_COLUMNS + ("flow_ul_s",),
           (EffectParameter("R_pa_per_ul_s", "Pa per ul/s", 0.0, (0.0, 5000.0),
                            (round(0.5 * R_CHANNEL, 1), round(R_CHANNEL + R_TUBING_1M, 1)),
                            50.0,
                            "pressure drop per flow rate between the gauge and the chamber; "
                            f"the paper's inlet channel alone (water, 0.5 x 3 mm, 150 um high) "
                            f"gives {R_CHANNEL:.0f}, 1 m of 0.5 mm bore tubing adds "
                            f"{R_TUBING_1M:.0f}"),),
           "Chamber pressure = gauge pressure - R Q (Hagen-Poiseuille, laminar). With one "
           "flow rate for all curves it is exactly a pressure offset p0 = R Q: vary the flow "
           "rate to tell them apart."),
    Effect("angle_offset", "Angle offset", "structural", BASE_COLUMNS,
           (EffectParameter("offset_deg", "deg", 0.0, (-30.0, 30.0), (-8.0, 8.0), 0.0,
                            "angle at zero pressure: pre-curvature from bonding, gravity sag, "
                            "or the zero of the angle reading"),),
           "angle += offset_deg at every pressure."),
    Effect("saturation", "Saturation of the bend", "structural", BASE_COLUMNS,
           (EffectParameter("theta_max_deg", "deg", math.inf, (20.0, math.inf), (45.0, math.inf),
                            300.0, "limit the bend approaches (self-contact of balloon and "
                            "body, full curl); the paper's model has none"),),
           "forward bend b -> theta_max tanh(b / theta_max): slope unchanged near zero, "
           "bends the exponential over at large angles."),
    Effect("reverse_bending", "Reverse bending below the transition", "structural",
           BASE_COLUMNS,
           (EffectParameter("depth_deg", "deg", 0.0, (0.0, 20.0), (0.0, 6.0), 0.5,
                            "largest bend towards the balloon (the paper neglects it)"),
            EffectParameter("p_r_pa", "Pa", math.nan, (20.0, 2000.0), (30.0, 600.0), 200.0,
                            "pressure of the deepest reverse bend", tested=False)),
           "angle -= depth (p/p_r) exp(1 - p/p_r): a dip towards the balloon at low pressure "
           "that fades once the balloon has formed."),
    Effect("viscoelastic_lag", "Viscoelastic lag", "structural", BASE_COLUMNS + ("time_s",),
           (EffectParameter("tau_v_s", "s", 0.0, (0.0, 30.0), (0.0, 10.0), 0.5,
                            "relaxation time of the angle towards its static value (silicone "
                            "creep)"),),
           "d angle/dt = (static(p(t)) - angle) / tau_v along each curve's time_s, starting "
           "at rest; pressure is linear between samples."),
    Effect("stiffness_scale", "Stiffness scale", "parameter", BASE_COLUMNS,
           (EffectParameter("s", "-", 1.0, (0.3, 3.0), (0.6, 1.6), 1.0,
                            "measured over nominal stiffness of the silicones (mixing, cure)"),),
           "All moduli x s is the same actuator at pressure p/s (hyperelastic scaling), so "
           "tau -> s tau at every thickness and A is unchanged."),
    Effect("membrane_thickness_bias", "Membrane thickness bias", "parameter", BASE_COLUMNS,
           (EffectParameter("dt_mm", "mm", 0.0, (-0.35, 0.5), (-0.15, 0.15), 0.0,
                            "fabricated minus nominal membrane thickness (spin coating)"),),
           "t -> t + dt in tau = a_t log10(b_t t): a shift of tau that is largest for thin "
           "membranes (unlike stiffness_scale, which scales every tau alike)."),
)

EFFECTS = {e.id: e for e in CATALOGUE}
EFFECT_IDS = tuple(EFFECTS)


def catalogue_dicts() -> list[dict[str, object]]:
    """The catalogue as plain data (GET /v1/effects)."""
    return [e.as_dict() for e in CATALOGUE]
