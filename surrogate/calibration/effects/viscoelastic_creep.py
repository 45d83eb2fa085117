"""Viscoelastic creep of the silicones: the angle answers a change of pressure partly at
once and partly with a delay (one-term Prony series in creep)."""

from __future__ import annotations

import numpy as np

from surrogate.calibration.effects._base import Effect, EffectParameter


def prony_lag(static_deg: np.ndarray, time_s: np.ndarray, valid: np.ndarray,
              g: float, tau_s: float) -> np.ndarray:
    """out = (1 - g) static + g y,  dy/dt = (static - y) / tau, y(0) = static(0) (the
    curve starts at rest); arrays (n_curves, m) along each curve's time, ``valid`` marks
    real entries (padding after the last). Exact for a static value linear between the
    given instants. The bend's creep (0 < g < 1, in deg) and, with -g, the pressure's
    relaxation at a held volume (pressure_relaxation.py, in Pa)."""
    dt = np.where(valid[:, 1:], np.diff(time_s, axis=1), 1.0)
    dt = np.maximum(dt, 1e-9)
    decay = np.exp(-dt / tau_s)
    gain = tau_s / dt * (1.0 - decay)  # exact response to a ramp over the interval
    u0, u1 = static_deg[:, :-1], static_deg[:, 1:]
    # y_j = u1 - (u1 - u0) gain + (y_{j-1} - u0) decay: the terms without y made for every
    # step at once, the steps along time as rows (transposed, contiguous); the same
    # operations in the same order as step by step (the same numbers to the last bit),
    # in ~half the time (a calibration evaluates this ~7,000 times); a step where every
    # curve has a reading (all but the padded tails) needs no choice
    ramp = (u1 - (u1 - u0) * gain).T.copy()
    u0, decay, valid = u0.T.copy(), decay.T.copy(), valid[:, 1:].T.copy()
    every = valid.all(axis=1)
    out = np.empty(static_deg.shape[::-1])
    y = out[0] = static_deg[:, 0]
    for j in range(len(ramp)):
        step = ramp[j] + (y - u0[j]) * decay[j]
        y = out[j + 1] = step if every[j] else np.where(valid[j], step, y)
    return (1.0 - g) * static_deg + g * out.T


class ViscoelasticCreep(Effect):
    id = "viscoelastic_creep"
    title = "Viscoelastic creep (one-term Prony)"
    measure_directly = "hold the volume for 5-10 s and watch the angle creep"
    stage = "time"
    kind = "time"
    needs = ("time_s",)
    parameters = (
        EffectParameter("g_retarded", "-", 0.0, (0.0, 1.0), (0.0, 0.6), 0.1,
                        "retarded fraction of the bend: 1 - g answers at once, g after "
                        "tau (silicones: 0.05-0.3)"),
        EffectParameter("tau_retardation_s", "s", float("nan"), (0.05, 60.0), (0.1, 30.0),
                        2.0, "retardation time of the delayed part", tested=False),
    )
    description = ("angle = (1 - g) static + g y, dy/dt = (static - y)/tau along each "
                   "curve's time_s, from rest: the angle creeps on during a hold and lags "
                   "on unloading (a loop).")

    def not_identifiable(self, data):
        if not data.has_time:
            return ("needs the time of each reading", "record time_s")
        if not data.pump_varies:
            return ("loading at one flow rate only: a lag is indistinguishable from a "
                    "pressure shift or a shape misfit of the baseline along the curve",
                    "hold the pressure for 5-10 s, record the unloading, or repeat at a "
                    "second flow rate")
        return None

    def lag(self, static_deg, time_s, valid, values):
        return prony_lag(static_deg, time_s, valid, values["g_retarded"],
                         values["tau_retardation_s"])

    def interpret(self, params, data):
        g, tau = params["g_retarded"], params["tau_retardation_s"]
        return (f"The bend creeps: {100 * g['value']:.0f} +/- {100 * g['sd']:.0f} % of it "
                f"arrives with a retardation time of {tau['value']:.1f} +/- "
                f"{tau['sd']:.1f} s (silicone viscoelasticity): readings taken while pumping "
                "understate the static angle; hold each pressure for about "
                f"{3 * tau['value']:.0f} s, or pump more slowly.")


EFFECT = ViscoelasticCreep()
