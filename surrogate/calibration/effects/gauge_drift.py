"""A gauge whose zero drifts during a run (it warms up, or the room or the fluid does):
its reading runs away from the chamber's pressure at a steady rate from the pump's
start, when it was zeroed.

    p_gauge = p_chamber + r t          (t = time_s, from the pump's start)

A pressure offset is the same at every instant; a drift grows along each curve, on
loading, in a hold and on unloading alike, so a hold and the unloading tell the two
apart. Read by injected volume only (the gauge against the pump's volume, where the
chamber's pressure is the baseline's at that volume): against the gauge pressure a drift
would be read into the bend of every later reading."""

from __future__ import annotations

from surrogate.calibration.effects._base import Effect, EffectParameter, needs_volume_channel

# The plausible range's top: a low-cost piezoresistive sensor warming after power-up moves
# a few Pa per second; 10 Pa/s is 300 Pa over a 30 s curve, a sixth of its range.
PLAUSIBLE_MAX_PA_PER_S = 10.0


class GaugeDrift(Effect):
    id = "gauge_drift"
    title = "Gauge drift during a run"
    measure_directly = ("log the gauge open to the atmosphere for a minute after powering it "
                        "up, and zero it just before each run")
    stage = "time"
    kind = "measurement"
    lags = "gauge"
    needs = ("time_s", "flow_ul_s")
    parameters = (EffectParameter(
        "drift_pa_per_s", "Pa/s", 0.0, (-100.0, 100.0),
        (-PLAUSIBLE_MAX_PA_PER_S, PLAUSIBLE_MAX_PA_PER_S), 0.0,
        "how fast the gauge's reading runs away from the chamber's pressure after the "
        "pump starts (its zero drifting with warm-up or temperature)"),)
    description = ("p_gauge = p_chamber + r t along each curve's time from the pump's start: "
                   "a zero error that grows during the run, unlike a pressure offset.")

    def not_identifiable(self, data):
        if not data.by_volume:
            return needs_volume_channel(data, "the gauge")
        if not data.pump_varies:
            return ("loading at one flow rate only: a gauge running away along the curve is "
                    "indistinguishable from a stiffer chamber or a pressure gain",
                    "hold the volume for 10 s, or record the unloading")
        return None

    def lag(self, static_pa, time_s, valid, values):
        return static_pa + values["drift_pa_per_s"] * time_s

    def interpret(self, params, data):
        v = params["drift_pa_per_s"]
        r = v["value"]
        said = (f"The gauge drifts: its reading runs {'above' if r >= 0 else 'below'} the "
                f"chamber by {abs(r):.2g} +/- {v['sd']:.2g} Pa per second of the run "
                f"({abs(r) * 30:.0f} Pa after 30 s). Let the sensor warm up before zeroing "
                "it, zero it just before each run, and keep it out of the lamp's heat.")
        if r < 0 and data.get("unloading"):      # the report's data: readings unloading
            said += (" A gauge falling below the chamber late in a run that unloads is "
                     "also what the silicone's softening on unloading shows (the Mullins "
                     "effect, a hysteresis the catalogue does not hold: the unloading's "
                     "pressure below the loading's at the same volume): a drift leaves the "
                     "gauge off at rest after the run, softening does not, so read the "
                     "gauge at rest for a few seconds after each run to tell them apart.")
        return said


EFFECT = GaugeDrift()
