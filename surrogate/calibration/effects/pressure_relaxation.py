"""Stress relaxation of the silicones, seen on the gauge: under a syringe pump the chamber's
volume is set, and the pressure needed to hold it is higher at first than at rest.

A standard linear solid (one-term Prony series in relaxation) with the baseline as the
relaxed (long-term) response, p_static(V):

    p = (1 + g) p_static - g y,    dy/dt = (p_static - y) / tau,   from rest,

so the pressure overshoots p_static while fluid is pumped in (by g tau Q dp/dV once the
loading has run a few tau), relaxes back to it during a hold and undershoots while fluid
is withdrawn. The bend at a held volume is set by that volume (the balloon must hold it)
and is read from the baseline unchanged. The same exact-for-a-ramp integration as the
bend's creep (``viscoelastic_creep.prony_lag``, with -g).

Apart from the inlet's resistance (hydraulic_resistance, a step of R Q at every change of
the pump) by its decay over tau during a hold and by its size growing with the
chamber's stiffness dp/dV; read by injected volume only (the gauge against the pump's
volume)."""

from __future__ import annotations

from surrogate.calibration.effects._base import Effect, EffectParameter, needs_volume_channel
from surrogate.calibration.effects.viscoelastic_creep import prony_lag


class PressureRelaxation(Effect):
    id = "pressure_relaxation"
    title = "Stress relaxation at held volume (one-term Prony)"
    measure_directly = ("stop the pump mid-curve for 10-20 s and log the gauge: it decays "
                        "to its relaxed value with the relaxation time, the bend stays")
    stage = "time"
    kind = "time"
    lags = "gauge"
    needs = ("time_s", "flow_ul_s")
    parameters = (
        EffectParameter("g_relaxing", "-", 0.0, (0.0, 1.0), (0.0, 0.5), 0.1,
                        "how much stiffer the silicones answer at once than at rest: the "
                        "pressure at a held volume relaxes from (1 + g) times its relaxed "
                        "value (silicones: 0.05-0.3)"),
        EffectParameter("tau_relaxation_s", "s", float("nan"), (0.05, 60.0), (0.1, 30.0),
                        2.0, "relaxation time of the pressure at a held volume",
                        tested=False),
    )
    description = ("p = (1 + g) p_static - g y, dy/dt = (p_static - y)/tau along each "
                   "curve's time, from rest, with p_static the baseline's pressure at the "
                   "injected volume: the gauge overshoots while pumping, relaxes during a "
                   "hold, undershoots while withdrawing; the bend follows the volume.")

    def not_identifiable(self, data):
        if not data.by_volume:
            return needs_volume_channel(data, "the gauge")
        if not data.pump_varies:
            return ("loading at one flow rate only: the overshoot is indistinguishable from "
                    "the inlet's R Q or a pressure offset",
                    "hold the volume for 5-10 s, record the unloading, or repeat at a "
                    "second flow rate")
        return None

    def lag(self, static_pa, time_s, valid, values):
        return prony_lag(static_pa, time_s, valid, -values["g_relaxing"],
                         values["tau_relaxation_s"])

    def interpret(self, params, data):
        g, tau = params["g_relaxing"], params["tau_relaxation_s"]
        return (f"The pressure relaxes at a held volume: the silicones answer "
                f"{100 * g['value']:.0f} +/- {100 * g['sd']:.0f} % stiffer at once than at "
                f"rest, relaxing with a time of {tau['value']:.1f} +/- {tau['sd']:.1f} s "
                "(viscoelasticity). Gauge readings taken while pumping overstate the "
                f"relaxed pressure; read it after a hold of about {3 * tau['value']:.0f} s. "
                "The bend at a volume is not affected.")


EFFECT = PressureRelaxation()
