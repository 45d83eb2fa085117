"""Compliance of the fluid line: air trapped in the syringe or tubing, or soft tubing,
takes up part of the pump's stroke as the pressure rises, so the chamber receives less
than the pump delivered and gets it back as the pressure falls.

    V_pump = V_chamber + C p_chamber

An air bubble of volume V_air at atmospheric pressure P_atm (isothermal, Boyle) gives
up V_air p / (P_atm + p): C = V_air / P_atm to within p / P_atm (2 % at 2 kPa, the top of
these actuators' range). Tubing of bore r, wall w, length l and modulus E gives
C = 2 pi r^3 l / (E w) (thin wall). The pressure in the line is taken as the chamber's:
the inlet's R Q drop (hydraulic_resistance) moves it by tens of Pa, a few % of C p.

Only the injected volume tells it: against the gauge pressure the bend is unchanged,
against the pump's volume both the bend and the gauge's pressure lag. So it is read by
volume only (the pump's two observables, docs/calibration.md)."""

from __future__ import annotations

import numpy as np

from surrogate.calibration.effects._base import Effect, EffectParameter, needs_volume_channel

ATMOSPHERE_KPA = 101.325
# Tubing is not described in the paper: silicone tubing of 1 mm bore, 0.5 mm wall, 1 m
# long, E ~ 1 MPa (2 pi r^3 l / (E w) = 1.6 ul/kPa), for the interpretation's scale.
SILICONE_TUBING_1M_UL_PER_KPA = 2 * np.pi * 0.5**3 * 1000.0 / (1e6 * 0.5) * 1e3
# The plausible range's top: about 1 ml of air at atmospheric pressure (a syringe filled
# carelessly), or several metres of soft tubing.
PLAUSIBLE_MAX_UL_PER_KPA = 10.0


class LineCompliance(Effect):
    id = "line_compliance"
    title = "Line compliance (air in the line, soft tubing)"
    measure_directly = ("block the chip's inlet, pump 5 ul and read the gauge: a stiff, "
                        "air-free line rises by kPa at once; C = 5 ul / the rise")
    stage = "volume"
    kind = "measurement"
    needs = ("time_s", "flow_ul_s")
    parameters = (EffectParameter(
        "C_ul_per_kpa", "ul per kPa", 0.0, (0.0, 30.0), (0.0, PLAUSIBLE_MAX_UL_PER_KPA), 0.5,
        "volume the line takes up per kPa of pressure: an air bubble of V ul at "
        f"atmospheric pressure gives V / {ATMOSPHERE_KPA:.1f}; 1 m of soft silicone tubing "
        f"(1 mm bore, 0.5 mm wall) about {SILICONE_TUBING_1M_UL_PER_KPA:.1f}"),)
    description = ("V_chamber from V_pump = V_chamber + C p_chamber along the baseline's "
                   "pressure-volume curve of the (changed) design: the bend and the gauge "
                   "lag the pump's volume alike, the bend against the gauge is unchanged. "
                   "Read by injected volume only.")

    def not_identifiable(self, data):
        return needs_volume_channel(data)     # against the gauge it changes nothing

    def chamber_volume(self, pump_ul, v_grid_ul, p_grid_pa, design_index, values):
        c_ul_per_pa = values["C_ul_per_kpa"] * 1e-3
        if c_ul_per_pa == 0.0:
            return pump_ul
        return chamber_volume_ul(pump_ul, v_grid_ul, p_grid_pa, design_index, c_ul_per_pa)

    def interpret(self, params, data):
        v = params["C_ul_per_kpa"]
        c = v["value"]
        return (f"Line compliance {c:.3g} +/- {v['sd']:.2g} ul per kPa: the chamber received "
                f"{c:.2g} ul less than the pump delivered for every kPa of pressure, as "
                f"about {c * ATMOSPHERE_KPA:.0f} ul of air in the syringe or tubing would "
                "take up (or soft tubing). Prime the line free of air and use stiff tubing, "
                "or read the volume at the chip; against the gauge pressure the bend is not "
                "affected.")


def chamber_volume_ul(pump_ul: np.ndarray, v_grid_ul: np.ndarray, p_grid_pa: np.ndarray,
                      design_index: np.ndarray, c_ul_per_pa: float) -> np.ndarray:
    """The chamber's volume (ul) at each row's pump volume ``pump_ul``, its design's
    chamber pressure being ``p_grid_pa[design]`` (Pa) at chamber volumes ``v_grid_ul``:
    V_pump = V + C p(V) inverted along the grid (linear between nodes). The pump volume
    rises with V wherever p does; past a pressure maximum it is kept non-decreasing (the
    chamber then takes the whole stroke). Past the grid's last finite pressure, or at a
    NaN pump volume: NaN."""
    pump = np.asarray(pump_ul, float)
    out = np.full(pump.shape, np.nan)
    for d in np.unique(design_index):
        rows = design_index == d
        p = p_grid_pa[d]
        finite = np.isfinite(p)
        end = int(np.argmin(finite)) if not finite.all() else p.size
        if end < 2:
            continue
        v = v_grid_ul[:end]
        along = np.maximum.accumulate(v + c_ul_per_pa * np.maximum(p[:end], 0.0))
        x = pump[rows]
        inside = np.isfinite(x) & (x <= along[-1])
        out[rows] = np.where(inside, np.interp(np.where(inside, x, 0.0), along, v), np.nan)
    return out


EFFECT = LineCompliance()
