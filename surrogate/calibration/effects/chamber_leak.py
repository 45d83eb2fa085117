"""A leak: a pinhole in the membrane, an unbonded rim or a loose inlet lets fluid out at a
rate set by the chamber's pressure, so the chamber holds less than the pump delivered, the
more so the longer and the higher it was pressurised.

    dV_lost/dt = G p_chamber(V_pump - V_lost)         (laminar: rate proportional to p)

integrated along each curve's time from rest (Heun's method on the augmented model's
substeps, a quarter of a reading interval). Its sign is a hold at which the bend and the
gauge both fall while the pump stands still; a compliant line (line_compliance) gives
back what it took and does nothing during a hold, the silicones' creep raises the bend
there, their relaxation lowers the gauge alone. Read by injected volume only."""

from __future__ import annotations

import numpy as np

from surrogate.calibration.effects._base import Effect, EffectParameter, needs_volume_channel

# The plausible range's top: 5 ul/s per kPa empties a 20 ul chamber held at 1 kPa in 4 s;
# a leak that fast is seen by eye, not fitted.
PLAUSIBLE_MAX_UL_S_PER_KPA = 5.0


class ChamberLeak(Effect):
    id = "chamber_leak"
    title = "Leak from the chamber or inlet"
    measure_directly = ("fill to mid-range, stop the pump and log the gauge and the bend for "
                        "30 s: a sealed actuator holds both (the gauge may relax a little), "
                        "a leaking one loses both; look for bubbles under water")
    stage = "time"
    kind = "physical"
    lags = "volume"
    needs = ("time_s", "flow_ul_s")
    parameters = (EffectParameter(
        "G_ul_s_per_kpa", "ul/s per kPa", 0.0, (0.0, 20.0), (0.0, PLAUSIBLE_MAX_UL_S_PER_KPA),
        0.2, "volume lost per second per kPa of chamber pressure (laminar leak conductance)"),)
    description = ("dV_lost/dt = G p_chamber along each curve's time, from rest: the chamber "
                   "holds the pump's volume less what leaked, the bend and the gauge read "
                   "there; both fall during a hold. Read by injected volume only.")

    def not_identifiable(self, data):
        if not data.by_volume:
            return needs_volume_channel(data)
        if not data.pump_varies:
            return ("loading at one flow rate only: a loss growing along the curve is "
                    "indistinguishable from a compliant line or a softer chamber",
                    "hold the volume for 10 s (a leak shows as a falling bend and gauge), or "
                    "repeat at a second flow rate")
        return None

    def delivered_volume(self, pump_ul, time_s, valid, pressure_at, values):
        g_ul_s_per_pa = values["G_ul_s_per_kpa"] * 1e-3
        if g_ul_s_per_pa == 0.0:
            return pump_ul
        return leaked_volume_ul(pump_ul, time_s, valid, pressure_at, g_ul_s_per_pa)

    def interpret(self, params, data):
        v = params["G_ul_s_per_kpa"]
        g = v["value"]
        return (f"The chamber leaks: {g:.3g} +/- {v['sd']:.2g} ul/s for every kPa inside it, "
                f"so a 10 s hold at 1 kPa loses about {10 * g:.2g} ul and the bend and the "
                "gauge fall while the pump stands still. Look for a pinhole in the membrane, "
                "an unbonded rim or a loose inlet (under water, bubbles show it).")


def leaked_volume_ul(pump_ul: np.ndarray, time_s: np.ndarray, valid: np.ndarray,
                     pressure_at, g_ul_s_per_pa: float) -> np.ndarray:
    """The volume (ul) left in the line and chamber at each instant (n_curves, m) of the
    pump's volume ``pump_ul`` at times ``time_s``, losing G p per second, p the chamber's
    pressure (Pa) there: ``pressure_at(volume_ul)``, one volume per curve (NaN past the
    baseline's range counts as no loss). Heun's method along each curve from rest;
    ``valid`` marks real entries (padding after the last)."""
    out = np.array(pump_ul, float)
    lost = np.zeros(out.shape[0])

    def rate(volume: np.ndarray) -> np.ndarray:
        return g_ul_s_per_pa * np.fmax(pressure_at(volume), 0.0)    # fmax: NaN -> 0

    start = rate(out[:, 0])
    for j in range(1, out.shape[1]):
        dt = np.where(valid[:, j], time_s[:, j] - time_s[:, j - 1], 0.0)
        guess = np.maximum(pump_ul[:, j] - lost - start * dt, 0.0)
        lost = np.minimum(lost + 0.5 * dt * (start + rate(guess)), pump_ul[:, j])
        out[:, j] = np.maximum(pump_ul[:, j] - lost, 0.0)
        start = rate(out[:, j])
    return out


EFFECT = ChamberLeak()
