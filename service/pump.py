"""The syringe-pump view of a prediction, for HTTP and the CLI alike.

A forward question is asked on exactly one axis: chamber (or pump-gauge) pressures (Pa),
injected volumes (ul), or times (s) at a flow rate (ul/s: volume = flow x time, the pump
starting from the undeformed state); the answer carries every axis it can (pressure,
volume, time when a flow rate is given) with the angle and force. An inverse question
(target angles of one design) is answered as the chamber pressure, the injected volume
and, at a flow rate, the time, each with its band.

With an ``Inlet`` (surrogate/hydraulics.py) and a flow rate the answer also gives the
pressure a gauge at the pump reads, p_pump = p_chamber + R Q (steady flow); every answer
says which site each of its pressure fields reports (``pressure_sites``).

The pump's flow limits (MIN_FLOW_UL_S, MAX_FLOW_UL_S, FLOW_RANGE) are
``surrogate.volume_control``'s, re-exported here: the design search's time targets read
the same table.

Errors are ``InputError`` naming the request field (``volumes_ul``, ``flow_ul_s``, ...);
the route locates them in the body, the CLI names its flag.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from solver.errors import InputError
from surrogate.hydraulics import NEGLIGIBLE_TIME_CONSTANT_S, STEADY_TIME_CONSTANTS, Inlet
from surrogate.predictor import FE_PRESSURE_STOP_PA, normal_or_zero, pressure_stop_reason
from surrogate.volume_control import (
    FLOW_RANGE,
    MAX_FLOW_UL_S,
    MAX_TIME_S,
    MIN_FLOW_UL_S,
    cut_past_longest_time,
)

# request field -> (lowest, highest, unit): the one table of the axes' limits (the HTTP
# schema's Field limits and the CLI's checks)
AXES: dict[str, tuple[float, float, str]] = {
    "pressures_pa": (0.0, FE_PRESSURE_STOP_PA, "Pa"),   # the default FE's pressure stop
    "volumes_ul": (0.0, 10000.0, "ul"),
    "times_s": (0.0, MAX_TIME_S, "s"),
}
PRESSURE_SITES = ("chamber", "pump_gauge")
MAX_ANGLE_DEG = 360.0      # |target angle| <= this (a full turn), degrees


@dataclass(frozen=True)
class PumpQuestion:
    """What a forward request asks: one of the three axes, the flow rate, the inlet."""

    pressures_pa: Sequence[float] | None = None
    volumes_ul: Sequence[float] | None = None
    times_s: Sequence[float] | None = None
    flow_ul_s: float | None = None
    inlet: Inlet | None = None
    pressures_at: str = "chamber"      # the site the given pressures_pa were read at

    def axis(self) -> str:
        """The one axis asked; InputError naming the field otherwise."""
        given = [n for n in AXES if getattr(self, n) is not None]
        if len(given) != 1:
            raise InputError(given[1] if given else "pressures_pa",
                             "give exactly one of pressures_pa, volumes_ul, or times_s; got "
                             f"{', '.join(given) or 'none'}",
                             "; or ".join(f"each {lo:g} <= {n} <= {hi:g} ({u})"
                                          for n, (lo, hi, u) in AXES.items())
                             + " with flow_ul_s (ul/s)")
        name = given[0]
        lo, hi, unit = AXES[name]
        values = np.asarray(getattr(self, name), float)
        if values.size == 0 or not np.all(np.isfinite(values)):
            raise InputError(name, "needs one or more finite numbers", f"{lo:g}..{hi:g} {unit}")
        bad = values[(values < lo) | (values > hi)]
        if bad.size:
            raise InputError(name, f"{bad[0]:g} {unit} is out of range", f"{lo:g}..{hi:g} {unit}")
        check_flow(self.flow_ul_s, self.inlet, name == "times_s")
        if self.pressures_at not in PRESSURE_SITES:
            raise InputError("pressures_at", f"got {self.pressures_at!r}", "chamber, pump_gauge")
        if self.pressures_at == "pump_gauge" and (name != "pressures_pa" or self.inlet is None):
            raise InputError("pressures_at", "pump_gauge pressures need pressures_pa, an inlet "
                             "and flow_ul_s", "chamber, or pump_gauge with pressures_pa, "
                             "inlet and flow_ul_s")
        return name


def check_flow(flow_ul_s: float | None, inlet: Inlet | None, by_time: bool = False) -> None:
    """The flow rate in range, and given where times or an inlet need it."""
    if flow_ul_s is not None and not (math.isfinite(flow_ul_s)
                                      and MIN_FLOW_UL_S <= flow_ul_s <= MAX_FLOW_UL_S):
        raise InputError("flow_ul_s", f"{flow_ul_s:g} ul/s is out of range", FLOW_RANGE)
    if flow_ul_s is None and by_time:
        raise InputError("flow_ul_s", "times_s needs the pump's flow rate",
                         f"{FLOW_RANGE} with times_s")
    if flow_ul_s is None and inlet is not None:
        raise InputError("flow_ul_s", "the inlet's pressure drop R Q needs the flow rate",
                         f"{FLOW_RANGE} with inlet")


def inlet_drop(inlet: Inlet | None, flow_ul_s: float | None) -> dict[str, Any] | None:
    """The inlet as the answer reports it, with R (Pa per ul/s), R Q (Pa) and Re."""
    if inlet is None or flow_ul_s is None:
        return None
    drop = inlet.pressure_drop_pa(flow_ul_s)   # refuses a flow that is not laminar
    return {**inlet.as_dict(), "resistance_pa_per_ul_s": inlet.resistance_pa_per_ul_s,
            "flow_ul_s": flow_ul_s, "pressure_drop_pa": drop,
            "reynolds_number": inlet.reynolds_number(flow_ul_s),
            "time_constant_s": inlet.time_constant_s}


def _pump_gauge(body: dict[str, Any], drop: dict[str, Any], what: str = "point(s)") -> None:
    """In place: the pump gauge's reading, chamber pressure + R Q, where it is read; none
    before STEADY_TIME_CONSTANTS time constants of the line after the pump starts (time_s:
    volume / flow), flag ``pump_pressure_not_steady``. With the fluid's compressibility
    alone (tau, ``Inlet.time_constant_s``, a lower bound) 100 Pa s in 100 m of 0.05 mm
    tubing read 1.6e14 Pa, a steady R Q never reached (tau ~ 6e6 s)."""
    body["pump_pressure_pa"] = _plus(body["pressure_pa"], drop["pressure_drop_pa"])
    body["pressure_sites"]["pump_pressure_pa"] = "pump_gauge"
    tau = drop["time_constant_s"]
    if tau <= NEGLIGIBLE_TIME_CONSTANT_S:
        return
    times = body.get("time_s") or [None] * len(body["pump_pressure_pa"])
    early = [t is None or t < STEADY_TIME_CONSTANTS * tau for t in times]
    if not any(early):
        return
    body["pump_pressure_pa"] = [None if e else v
                                for v, e in zip(body["pump_pressure_pa"], early, strict=True)]
    body["validity"]["flags"].append("pump_pressure_not_steady")
    body["validity"]["messages"].append(
        f"no pump-gauge pressure at {sum(early)} {what}: the fluid in the inlet "
        f"({drop['resistance_pa_per_ul_s']:.3g} Pa per ul/s, compressible) takes "
        f"tau = {tau:.3g} s or more to carry the flow, so the "
        f"gauge reads R Q = {drop['pressure_drop_pa']:.3g} Pa above the chamber only "
        f"after ~{STEADY_TIME_CONSTANTS:g} tau ({STEADY_TIME_CONSTANTS * tau:.3g} s), and "
        f"until then the chamber's volume lags the pump's by up to Q tau = "
        f"{drop['flow_ul_s'] * tau:.3g} ul; a shorter or wider line, or a thinner fluid, "
        "shortens it")


def _plus(values: list[float | None], offset: float) -> list[float | None]:
    return [None if v is None else v + offset for v in values]


def _over(values: list[float | None] | None, flow: float) -> list[float | None] | None:
    return None if values is None else [None if v is None else v / flow for v in values]


# Every pressure at or below this (Pa), none above: a lab that typed kPa (1, 1.5, 2) gets
# an answer of 0.001 deg and, with this flag, the reason.
KPA_LOOKALIKE_PA = 20.0


def predict_answer(surrogate: Any, design: Any, question: PumpQuestion, model: str,
                   level: float) -> dict[str, Any]:
    """The plain-data answer of /v1/predict and ``balloon predict`` (PredictResponse)."""
    from service.convert import (  # service.schemas imports AXES from here
        finite_list,
        prediction_body,
    )

    axis = question.axis()
    q = question.flow_ul_s
    inlet = inlet_drop(question.inlet, q)
    if axis == "pressures_pa":
        p = normal_or_zero(question.pressures_pa)    # 1e-310 Pa is 0 Pa
        if question.pressures_at == "pump_gauge" and inlet is not None:
            drop = inlet["pressure_drop_pa"]
            tau = inlet["time_constant_s"]
            if tau > NEGLIGIBLE_TIME_CONSTANT_S:
                raise InputError("pressures_at", f"the inlet's fluid takes tau = {tau:.3g} s "
                                 "to carry the flow, so a gauge reading is not the chamber's "
                                 "plus R Q until long after the pump starts",
                                 '"chamber", or an inlet whose time constant is at most '
                                 f"{NEGLIGIBLE_TIME_CONSTANT_S:g} s")
            top = AXES["pressures_pa"][1]
            if drop >= top:      # no reading the field takes is above it
                raise InputError("flow_ul_s", f"the inlet's drop R Q = {drop:.1f} Pa at "
                                 f"{q:g} ul/s is above every pump-gauge reading "
                                 f"pressures_pa takes (at most {top:g} Pa)", f"flow_ul_s < "
                                 f"{top / inlet['resistance_pa_per_ul_s']:.4g} ul/s with "
                                 "this inlet")
            if (p < drop).any():
                raise InputError("pressures_pa", f"{p.min():g} Pa at the pump gauge is below "
                                 f"the inlet's drop R Q = {drop:.1f} Pa at {q:g} ul/s",
                                 f"{drop:.1f} <= pressures_pa <= {top:g} Pa at the pump "
                                 "gauge")
            p = p - drop
        prediction = surrogate.predict(design, p, level=level)
    else:
        by_volume = getattr(surrogate, "predict_volume", None)
        if by_volume is None:
            raise InputError(axis, f"model {model!r} answers by pressure only",
                             'model "emulator" for volumes and times')
        # subnormal inputs, and products of times and flow, are read as 0
        v = normal_or_zero(question.volumes_ul if axis == "volumes_ul"
                           else normal_or_zero(question.times_s) * float(q or 0))
        try:
            prediction = by_volume(design, v, level=level)
        except InputError as exc:   # volumes derived from times: name the field asked
            if exc.field != "volumes_ul" or axis == "volumes_ul":
                raise
            raise InputError(axis, exc.detail, exc.allowed) from None
    body = prediction_body(prediction, model, level, design)
    body["asked"] = axis
    _cut_at_pressure_stop(body)
    _range_within_pressure_stop(body, surrogate, design, level)
    if axis != "pressures_pa":
        _say_what_force_by_volume_is(body)
    if axis == "pressures_pa" and 0.0 < float(np.max(normal_or_zero(question.pressures_pa))) \
            <= KPA_LOOKALIKE_PA:
        body["validity"]["flags"].append("pressures_look_like_kpa")
        body["validity"]["messages"].append(
            f"every pressure asked is at most {KPA_LOOKALIKE_PA:g} Pa, where the box's "
            "designs bend by hundredths of a degree: pressures_pa is in Pa (1.5 kPa is "
            "1500)")
    body["pressure_sites"] = {"pressure_pa": "chamber"}
    if q is not None and body.get("volume_ul") is None:     # asked for, never dropped
        raise _no_volume(model)
    if q is not None:
        body["flow_ul_s"] = q
        body["time_s"] = (finite_list(question.times_s) if axis == "times_s"
                          else _over(body.get("volume_ul"), q))
        v_lim = body["validity"].get("fe_limit_volume_ul")
        if axis == "times_s" and v_lim is not None and "past_fe_range" in body["validity"]["flags"]:
            body["validity"]["messages"].append(   # 3 digits: 0.0284 s at 1000 ul/s, not 0.0
                f"at {q:g} ul/s the FE's range ends after {v_lim / q:.3g} s")
    if inlet is not None:
        body["inlet"] = inlet
        _pump_gauge(body, inlet)
    if q is not None:
        cut_past_longest_time(body, body["validity"], ("time_s",), q)
    return body


# what an answer gives at each point, cut where its chamber pressure is past the FE's stop
ANSWER_FIELDS = ("angle_deg", "lower_deg", "upper_deg", "force_mn", "force_lower_mn",
                 "force_upper_mn", "pressure_pa")
INVERSE_FIELDS = ("pressure_pa", "lower_pa", "upper_pa", "volume_ul", "volume_lower_ul",
                  "volume_upper_ul")


def _cut_at_pressure_stop(body: dict[str, Any], fields: tuple[str, ...] = ANSWER_FIELDS,
                          what: str = "point(s)") -> None:
    """In place: no number in ``fields`` where the answered chamber pressure is past the
    FE's pressure stop (SolverSettings.max_pressure_pa, the largest pressure /v1/predict
    takes), flag ``past_fe_pressure_stop``: two layers 50x their presets asked by volume
    were answered 76 deg at 104 kPa, where the default FE stops at 20 kPa. The fields
    derived from these (time, the pump gauge) are made after it."""
    p_stop = AXES["pressures_pa"][1]
    p = np.array([np.nan if v is None else v for v in body.get("pressure_pa") or []], float)
    over = p > p_stop
    if not over.any():
        return
    for name in fields:
        values = body.get(name)
        if values is not None:
            body[name] = [None if cut else v for v, cut in zip(values, over, strict=True)]
    if "past_fe_pressure_stop" not in body["validity"]["flags"]:   # the emulator says it too
        body["validity"]["flags"].append("past_fe_pressure_stop")
    body["validity"]["messages"].append(
        f"{int(over.sum())} {what} need a chamber pressure above {p_stop:g} Pa, where the "
        "FE stops (SolverSettings.max_pressure_pa) and the largest pressure the service "
        "answers: no number is given there")


TIME_FIELDS = ("time_s", "time_lower_s", "time_upper_s")


def _say_what_force_by_volume_is(body: dict[str, Any]) -> None:
    """In place: an answer by injected volume or time that gives a force says which force
    it is (flag ``force_at_free_tip_pressure``): the blocked tip's at the chamber pressure
    the free actuator reaches at that volume (``pressure_pa``), the only force the models
    give. A tip held blocked while the pump injects the same volume reaches a higher
    chamber pressure, and pushes harder: against the default FE, free and blocked, of three
    random box designs this force was 3-21 % below the blocked one at 40-95 % of the free
    curve's volume, 2-10 % below at 20 % (the audit of the thirty-seventh session)."""
    if not any(f is not None for f in body.get("force_mn") or ()):
        return
    body["validity"]["flags"].append("force_at_free_tip_pressure")
    body["validity"]["messages"].append(
        "force_mn is the blocked tip's force at the chamber pressure the free actuator "
        "reaches at each injected volume (pressure_pa), not the force of a tip held blocked "
        "while the pump injects that volume: blocked, the chamber reaches a higher pressure "
        "at the same volume and pushes harder (the FE: up to about a quarter)")


def _range_within_pressure_stop(body: dict[str, Any], surrogate: Any, design: Any,
                                level: float) -> None:
    """In place: where the model's FE range would end past the FE's pressure stop, it ends
    at the stop, with the angle and injected volume the model gives there: layers 50x
    their presets were told an FE range to 105843 Pa while every number past 20 kPa was
    withheld (past_fe_pressure_stop). The emulator ends its range there itself
    (``pressure_stop_angle``); this is for the models that do not."""
    p_stop = AXES["pressures_pa"][1]
    validity = body["validity"]
    limit = validity.get("fe_limit_pa")
    if not isinstance(limit, int | float) or limit <= p_stop:
        return
    at_stop = surrogate.predict(design, [p_stop], level=level)
    validity["fe_limit_pa"] = p_stop
    validity["fe_limit_angle_deg"] = float(at_stop.angle_deg[0])
    volume = getattr(at_stop, "volume_ul", None)
    if "fe_limit_volume_ul" in validity:
        validity["fe_limit_volume_ul"] = None if volume is None else float(volume[0])
    validity["fe_stop_reason"] = pressure_stop_reason(limit)


def _no_volume(model: str) -> InputError:
    """A flow rate asked of a model that gives no injected volume: refused, never dropped."""
    return InputError("flow_ul_s", f"model {model!r} gives no injected volume for this "
                      "design, so no time at a flow rate",
                      'omit flow_ul_s, or model "emulator" (or an exponential model fitted '
                      "from FE curves with volumes)")


def inverse_answer(surrogate: Any, design: Any, angles_deg: Sequence[float], model: str,
                   level: float, flow_ul_s: float | None = None, inlet: Inlet | None = None
                   ) -> dict[str, Any]:
    """Pressure, injected volume and (at ``flow_ul_s``) time for each target angle, with
    bands (PressureResponse of /v1/inverse/pressure, ``balloon inverse --angles-deg``)."""
    from service.convert import finite_list, jsonable

    angles = np.asarray(angles_deg, float)
    if angles.size == 0 or not np.all(np.isfinite(angles) & (np.abs(angles) <= MAX_ANGLE_DEG)):
        raise InputError("angles_deg", "needs one or more finite angles within a full turn",
                         f"each -{MAX_ANGLE_DEG:g} <= angles_deg <= {MAX_ANGLE_DEG:g}")
    check_flow(flow_ul_s, inlet)
    drop = inlet_drop(inlet, flow_ul_s)
    angles = normal_or_zero(angles)     # 1e-310 deg is 0 deg
    result = surrogate.inverse(design, angles, level=level)
    volume = getattr(result, "volume_ul", None)
    if flow_ul_s is not None and volume is None:    # asked for, never silently dropped
        raise _no_volume(model)
    body: dict[str, Any] = {
        "model": model, "level": level, "design": design.as_dict(),
        "angle_deg": finite_list(angles),
        "pressure_pa": finite_list(result.pressure_pa), "lower_pa": finite_list(result.lower_pa),
        "upper_pa": finite_list(result.upper_pa),
        "volume_ul": None if volume is None else finite_list(volume),
        "volume_lower_ul": None if volume is None else finite_list(result.volume_lower_ul),
        "volume_upper_ul": None if volume is None else finite_list(result.volume_upper_ul),
        "validity": jsonable(dict(result.validity)), "pressure_sites": {"pressure_pa": "chamber"}}
    # two layers 50x their presets needed 94 kPa for 45 deg
    _cut_at_pressure_stop(body, INVERSE_FIELDS, "angle(s)")
    _range_within_pressure_stop(body, surrogate, design, level)
    if flow_ul_s is not None:
        body["flow_ul_s"] = flow_ul_s
        for name in ("", "_lower", "_upper"):
            body[f"time{name}_s"] = _over(body[f"volume{name}_ul"], flow_ul_s)
    if drop is not None:
        body["inlet"] = drop
        _pump_gauge(body, drop, "angle(s)")
    if flow_ul_s is not None:
        cut_past_longest_time(body, body["validity"], TIME_FIELDS, flow_ul_s, "angle(s)")
    return body
