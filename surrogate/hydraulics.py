"""The inlet's hydraulic resistance: how much the pressure a gauge at the pump reads
exceeds the chamber's while fluid flows in (pure functions; lengths mm, Pa, ul/s).

Steady laminar (Hagen-Poiseuille) flow of a Newtonian fluid, the pressure drop linear in
the flow rate Q: p_pump = p_chamber + R Q, R = R_channel + R_tubing, in series.

- Rectangular channel of width w, height h (h <= w; the two are swapped otherwise),
  length L, the exact series solution for a rectangular duct (e.g. Bruus, Theoretical
  Microfluidics, eq. 4.46):

      R = 12 mu L / (w h^3) / (1 - (192 h / (pi^5 w)) sum_{n odd} tanh(n pi w / (2 h)) / n^5)

  (the common shortcut 1 - 0.63 h/w for the bracket is within 0.2 % for h <= w / 2 and
  13 % off for a square duct; the paper's 0.5 x 0.15 mm channel: 0.01 %).
- Round tube of bore d = 2 r: R = 8 mu L / (pi r^4).

Both hold while the flow is laminar: the Reynolds number rho U D_h / mu is refused above
``LAMINAR_REYNOLDS`` (water density assumed for rho). Entrance effects and the fluid's
inertia are neglected (at the paper's 2.5 ul/s: Re ~ 8).

R Q is the steady reading. The fluid in the line is compressible, so the line is a
compliance C = V_line / K (K the bulk modulus, water's; the tubing's walls add to it, so
this is a lower bound) behind the resistance: after the pump starts, the gauge rises to R Q
above the chamber with the time constant tau = R C, and the chamber's volume lags the
pump's by up to Q tau. For the paper's channel tau ~ 3e-9 s, with 300 mm of 0.8 mm tubing
~ 4e-6 s: nothing to say. A viscous fluid in a long fine tube (100 Pa s, 100 m of 0.05 mm)
gives tau ~ 6e6 s, where the steady R Q (1.6e14 Pa) is never read (two audits of the
thirty-seventh session): ``Inlet.time_constant_s``, and the answer withholds the gauge
before ``STEADY_TIME_CONSTANTS`` tau.
Units: 1 ul/s = 1e-9 m^3/s, so R in Pa per ul/s = R_SI * 1e-9.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from solver.errors import InputError

WATER_VISCOSITY_PA_S = 1.0e-3     # water at 20 degC
WATER_DENSITY_KG_M3 = 998.0       # water at 20 degC (Reynolds number only)
LAMINAR_REYNOLDS = 2000.0         # Hagen-Poiseuille is refused above this
WATER_BULK_MODULUS_PA = 2.2e9     # water at 20 degC: the line's compliance V / K
# The gauge reads R Q above the chamber from this many time constants on (the chamber's
# volume then lags the pump's by Q tau, 1 % of the volume injected or less); a time
# constant at or below NEGLIGIBLE_TIME_CONSTANT_S is below what a lab's gauge or camera
# resolves.
STEADY_TIME_CONSTANTS = 100.0
NEGLIGIBLE_TIME_CONSTANT_S = 1e-3

# The paper's inlet: a straight channel 0.5 mm wide, 3 mm long, 150 um high (SU-8 mould).
CHANNEL_WIDTH_MM = 0.5
CHANNEL_LENGTH_MM = 3.0
CHANNEL_HEIGHT_MM = 0.15

_SERIES_TERMS = 200   # odd n = 1 .. 399; the tail is below 1e-12 of the sum

# The inlet's allowed values, (lowest, highest), mm and Pa s: the one table of the Inlet
# and the HTTP schema (service.schemas.InletIn). Beyond them the numbers stop being an
# inlet: a viscosity of 1e308 Pa s made the pump-gauge pressure infinite.
LIMITS: dict[str, tuple[float, float]] = {
    "channel_width_mm": (0.005, 20.0), "channel_length_mm": (0.01, 1000.0),
    "channel_height_mm": (0.005, 20.0), "tubing_length_mm": (0.0, 1e5),
    "tubing_bore_mm": (0.05, 20.0), "viscosity_pa_s": (1e-4, 100.0)}


def rectangular_channel_resistance_pa_per_ul_s(length_mm: float, width_mm: float,
                                               height_mm: float,
                                               viscosity_pa_s: float = WATER_VISCOSITY_PA_S
                                               ) -> float:
    """Hagen-Poiseuille resistance of a rectangular duct (exact series), Pa per ul/s."""
    L, w, h = length_mm * 1e-3, width_mm * 1e-3, height_mm * 1e-3
    h, w = min(h, w), max(h, w)
    series = sum(math.tanh(n * math.pi * w / (2.0 * h)) / n**5
                 for n in range(1, 2 * _SERIES_TERMS, 2))
    bracket = 1.0 - 192.0 * h / (math.pi**5 * w) * series
    return 12.0 * viscosity_pa_s * L / (w * h**3 * bracket) * 1e-9


def round_tube_resistance_pa_per_ul_s(length_mm: float, bore_mm: float,
                                      viscosity_pa_s: float = WATER_VISCOSITY_PA_S) -> float:
    """Hagen-Poiseuille resistance of a round tube, R = 8 mu L / (pi r^4), Pa per ul/s."""
    r = 0.5 * bore_mm * 1e-3
    return 8.0 * viscosity_pa_s * length_mm * 1e-3 / (math.pi * r**4) * 1e-9


@dataclass(frozen=True)
class Inlet:
    """The path from the pump's gauge to the chamber: the inlet channel (default the
    paper's) and, when ``tubing_length_mm`` > 0, tubing of bore ``tubing_bore_mm``."""

    channel_width_mm: float = CHANNEL_WIDTH_MM
    channel_length_mm: float = CHANNEL_LENGTH_MM
    channel_height_mm: float = CHANNEL_HEIGHT_MM
    tubing_length_mm: float = 0.0
    tubing_bore_mm: float | None = None
    viscosity_pa_s: float = WATER_VISCOSITY_PA_S

    def __post_init__(self) -> None:
        for name, (lo, hi) in LIMITS.items():
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and lo <= value <= hi):
                raise InputError(f"inlet.{name}", f"got {value:g}",
                                 f"{lo:g} <= {name} <= {hi:g}")
        bore = self.tubing_bore_mm
        if self.tubing_length_mm > 0 and bore is None:
            raise InputError("inlet.tubing_bore_mm", "tubing of a given length needs its bore",
                             "> 0 mm with tubing_length_mm")

    @property
    def resistance_pa_per_ul_s(self) -> float:
        """R = R_channel + R_tubing, Pa per ul/s."""
        r = rectangular_channel_resistance_pa_per_ul_s(
            self.channel_length_mm, self.channel_width_mm, self.channel_height_mm,
            self.viscosity_pa_s)
        if self.tubing_length_mm > 0 and self.tubing_bore_mm:
            r += round_tube_resistance_pa_per_ul_s(self.tubing_length_mm, self.tubing_bore_mm,
                                                   self.viscosity_pa_s)
        return r

    @property
    def line_volume_ul(self) -> float:
        """The fluid between the gauge and the chamber: channel w h L plus tubing
        pi d^2 / 4 L, ul (mm^3)."""
        v = self.channel_width_mm * self.channel_height_mm * self.channel_length_mm
        if self.tubing_length_mm > 0 and self.tubing_bore_mm:
            v += math.pi * self.tubing_bore_mm**2 / 4.0 * self.tubing_length_mm
        return v

    @property
    def time_constant_s(self) -> float:
        """tau = R C, C = V_line / K the compressibility of the fluid in the line (s; a
        lower bound: elastic tubing walls add compliance)."""
        return self.resistance_pa_per_ul_s * self.line_volume_ul / WATER_BULK_MODULUS_PA

    def reynolds_number(self, flow_ul_s: float) -> float:
        """The largest Reynolds number on the path (channel, tubing) at ``flow_ul_s``."""
        q = flow_ul_s * 1e-9
        w, h = self.channel_width_mm * 1e-3, self.channel_height_mm * 1e-3
        re = WATER_DENSITY_KG_M3 * (q / (w * h)) * (2 * w * h / (w + h)) / self.viscosity_pa_s
        if self.tubing_length_mm > 0 and self.tubing_bore_mm:
            d = self.tubing_bore_mm * 1e-3
            re = max(re, WATER_DENSITY_KG_M3 * q / (math.pi * d * d / 4) * d
                     / self.viscosity_pa_s)
        return re

    def pressure_drop_pa(self, flow_ul_s: float) -> float:
        """R Q, Pa: how much the pump's gauge reads above the chamber at ``flow_ul_s``."""
        re = self.reynolds_number(flow_ul_s)
        if re > LAMINAR_REYNOLDS:
            raise InputError("flow_ul_s", f"{flow_ul_s:g} ul/s gives a Reynolds number of "
                             f"{re:.0f} in the inlet: not laminar, Hagen-Poiseuille does "
                             "not hold", f"a flow rate with Re <= {LAMINAR_REYNOLDS:g}")
        return self.resistance_pa_per_ul_s * flow_ul_s

    def as_dict(self) -> dict[str, float | None]:
        return asdict(self)
