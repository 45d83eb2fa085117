"""What a design search must meet: ``DesignTarget``, its kinds and the ranking objectives.

Targets (``DesignTarget.kind``; angles in deg, forces in mN, pressures in Pa, injected
volumes in ul, times in s, flow rates in ul/s):

    angle_at_pressure   reach |angle_deg| exactly at pressure_pa
    pressure_budget     reach |angle_deg| at a pressure of at most pressure_pa
    force_at_pressure   reach |force_mn| (blocked tip) exactly at pressure_pa
    angle_at_volume     reach |angle_deg| exactly at the injected volume_ul
    volume_budget       reach |angle_deg| with no more than volume_ul injected
    angle_at_time       reach |angle_deg| exactly after time_s at flow_ul_s
    time_budget         reach |angle_deg| within time_s at flow_ul_s

A syringe pump's targets (the last four) are met at an injected volume from the
undeformed state: volume = flow x time, within the FE's volume stop. The sign of the
angle (force) is the bending direction asked for: positive away from the membrane,
negative towards it. Objectives (lower score ranks first):

    pressure    pressure needed (pressure_budget)
    volume      injected volume needed (volume_budget, time_budget: time = volume / flow)
    margin      band upper end of the pressure (or volume) needed (the budgets)
    compact     chamber length L
    certainty   relative width of the prediction band at the target
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from solver.errors import InputError
from surrogate.predictor import FE_PRESSURE_STOP_PA, FE_VOLUME_STOP_UL, SMALLEST_NORMAL
from surrogate.volume_control import FLOW_RANGE, MAX_FLOW_UL_S, MAX_TIME_S, MIN_FLOW_UL_S

KINDS = ("angle_at_pressure", "pressure_budget", "force_at_pressure", "angle_at_volume",
         "volume_budget", "angle_at_time", "time_budget")
#: the syringe pump's targets: by injected volume, or by time at a flow rate
TIME_KINDS = ("angle_at_time", "time_budget")
VOLUME_KINDS = ("angle_at_volume", "volume_budget", *TIME_KINDS)
#: targets met within a budget (the others exactly)
BUDGET_KINDS = ("pressure_budget", "volume_budget", "time_budget")
#: the target a search answers when none is named (HTTP and CLI alike)
DEFAULT_KIND = "angle_at_pressure"
#: the largest target magnitudes taken: |angle| in deg, |force| in mN, a pressure in Pa
#: (a pressure budget; a pressure a target is met at exactly is at most the default FE's
#: pressure stop, FE_PRESSURE_STOP_PA: no design is answered past it)
MAX_TARGET = {"angle_deg": 360.0, "force_mn": 1e4, "pressure_pa": 1e6}
OBJECTIVES = ("pressure", "volume", "margin", "compact", "certainty")
DEFAULT_OBJECTIVE = {"angle_at_pressure": "certainty", "pressure_budget": "pressure",
                     "force_at_pressure": "certainty", "angle_at_volume": "certainty",
                     "volume_budget": "volume", "angle_at_time": "certainty",
                     "time_budget": "volume"}

def resolve_objective(target: DesignTarget, objective: str | None) -> str:
    """The ranking objective for ``target``: the given one, checked, or the target's
    default (InputError naming ``objective`` and the allowed values otherwise)."""
    objective = objective or DEFAULT_OBJECTIVE[target.kind]
    if objective not in OBJECTIVES:
        raise InputError("objective", f"unknown objective {objective!r}", " | ".join(OBJECTIVES))
    budget_of = {"pressure": ("pressure_budget",), "volume": ("volume_budget", "time_budget"),
                 "margin": BUDGET_KINDS}
    if objective in budget_of and target.kind not in budget_of[objective]:
        ranks = [o for o, kinds in budget_of.items() if target.kind in kinds]
        raise InputError("objective", f"{objective!r} ranks {' or '.join(budget_of[objective])}"
                         " targets only", " | ".join((*ranks, "certainty", "compact")))
    return objective


@dataclass(frozen=True)
class DesignTarget:
    """What the design must do; units in the names. See the module docstring. A pump's
    target gives volume_ul, or time_s with flow_ul_s, and no pressure_pa."""

    kind: str
    pressure_pa: float | None = None
    angle_deg: float | None = None
    force_mn: float | None = None
    volume_ul: float | None = None
    time_s: float | None = None
    flow_ul_s: float | None = None

    def validated(self) -> DesignTarget:
        if self.kind not in KINDS:
            raise InputError("kind", f"unknown target {self.kind!r}", " | ".join(KINDS))
        uses = self._fields()
        for name in ("pressure_pa", "volume_ul", "time_s", "flow_ul_s"):
            if name not in uses and getattr(self, name) is not None:   # never dropped
                raise InputError(name, f"the {self.kind} target does not use {name}",
                                 f"leave {name} out (the {self.kind} target takes "
                                 f"{', '.join(uses)})")
        if self.kind in TIME_KINDS:
            self._check_time()
        elif self.kind in VOLUME_KINDS:
            if not finite_number(self.volume_ul) or not (_positive(self.volume_ul)
                                                   and self.volume_ul <= FE_VOLUME_STOP_UL):
                raise InputError("volume_ul", f"the {self.kind} target needs an injected "
                                 "volume within the FE's volume stop, got "
                                 + _got(self.volume_ul),
                                 f"0 < volume_ul <= {FE_VOLUME_STOP_UL:g} ul")
        elif not finite_number(self.pressure_pa) or not (
                _positive(self.pressure_pa) and self.pressure_pa <= self.max_pressure_pa):
            within = "" if self.kind in BUDGET_KINDS else " within the FE's pressure stop"
            raise InputError("pressure_pa", f"the {self.kind} target needs a pressure{within}"
                             ", got "
                             + _got(self.pressure_pa),
                             f"0 < pressure_pa <= {self.max_pressure_pa:g} Pa")
        name = "force_mn" if self.kind == "force_at_pressure" else "angle_deg"
        value = getattr(self, name)
        if value is None or not finite_number(value) or not (_positive(abs(value))
                                                            and abs(value) <= MAX_TARGET[name]):
            unit = "mN" if name == "force_mn" else "deg"
            raise InputError(name, f"the {self.kind} target needs a non-zero {name} of "
                             f"at most {MAX_TARGET[name]:g} {unit}, got "
                             + _got(value),
                             f"0 < |{name}| <= {MAX_TARGET[name]:g} {unit}; "
                             "positive bends away from the membrane, negative towards it")
        other = "angle_deg" if name == "force_mn" else "force_mn"
        if getattr(self, other) is not None:    # given, never silently dropped
            raise InputError(other, f"the {self.kind} target does not use {other}",
                             f"leave {other} out (the {self.kind} target takes {name})")
        return self

    def _fields(self) -> tuple[str, ...]:
        """The fields besides the angle (or force) this kind of target reads."""
        if self.kind in TIME_KINDS:
            return ("time_s", "flow_ul_s")
        return ("volume_ul",) if self.kind in VOLUME_KINDS else ("pressure_pa",)

    def _check_time(self) -> None:
        """time_s and flow_ul_s given, in range, and injecting no more than the FE's
        volume stop (time x flow, from the undeformed state)."""
        if self.flow_ul_s is None or not finite_number(self.flow_ul_s) or not (
                MIN_FLOW_UL_S <= self.flow_ul_s <= MAX_FLOW_UL_S):
            raise InputError("flow_ul_s", f"the {self.kind} target needs the pump's flow "
                             "rate, got " + ("none" if self.flow_ul_s is None
                                             else repr(self.flow_ul_s)), FLOW_RANGE)
        if not finite_number(self.time_s) or not (_positive(self.time_s)
                                                  and self.time_s <= MAX_TIME_S):
            raise InputError("time_s", f"the {self.kind} target needs a time, got "
                             + _got(self.time_s),
                             f"0 < time_s <= {MAX_TIME_S:g} s")
        volume = self.time_s * self.flow_ul_s
        if volume > FE_VOLUME_STOP_UL:
            raise InputError("time_s", f"{self.time_s:g} s at {self.flow_ul_s:g} ul/s "
                             f"injects {volume:g} ul, past the FE's volume stop "
                             f"({FE_VOLUME_STOP_UL:g} ul): no design is answered there",
                             f"0 < time_s <= {FE_VOLUME_STOP_UL / self.flow_ul_s:.4g} s at "
                             f"{self.flow_ul_s:g} ul/s (time_s x flow_ul_s <= "
                             f"{FE_VOLUME_STOP_UL:g} ul)")

    @property
    def value(self) -> float:
        return abs(float(self.force_mn if self.kind == "force_at_pressure"
                         else self.angle_deg))  # type: ignore[arg-type]

    @property
    def by_volume(self) -> bool:
        """A syringe pump's target: met at (or within) an injected volume."""
        return self.kind in VOLUME_KINDS

    @property
    def max_pressure_pa(self) -> float:
        """The largest pressure the target takes, Pa: a budget any (``MAX_TARGET``), a
        pressure the target is met at exactly the default FE's pressure stop."""
        return MAX_TARGET["pressure_pa"] if self.kind in BUDGET_KINDS else FE_PRESSURE_STOP_PA

    @property
    def budget(self) -> bool:
        """Met within a budget (pressure, volume or time), not exactly."""
        return self.kind in BUDGET_KINDS

    @property
    def at(self) -> float:
        """Where the target is met: the pressure (Pa), or for a pump's target the injected
        volume (ul; time x flow for a time target)."""
        if self.kind in TIME_KINDS:
            return float(self.time_s) * float(self.flow_ul_s)  # type: ignore[arg-type]
        return float(self.volume_ul if self.by_volume else self.pressure_pa)  # type: ignore

    @property
    def at_field(self) -> str:
        """The field ``at`` is given by: pressure_pa, volume_ul or time_s."""
        return self._fields()[0]

    def at_text(self, exact: bool = False) -> str:
        """Where the target is met, in words: "at 1500 Pa", "at 20 ul injected", "after 8 s
        at 2.5 ul/s (20 ul injected)"; a budget's "within" unless ``exact``."""
        within = self.budget and not exact
        if self.kind in TIME_KINDS:
            return (f"{'within' if within else 'after'} {self.time_s:g} s at "
                    f"{self.flow_ul_s:g} ul/s ({self.at:.4g} ul injected)")
        where = "within" if within else "at"
        if self.by_volume:
            return f"{where} {self.at:.4g} ul injected"
        return f"{where} {self.at:g} Pa"

    def with_at(self, at: float) -> DesignTarget:
        """The same target met at ``at`` instead (Pa, or ul for a pump's target)."""
        if self.kind in TIME_KINDS:
            return replace(self, time_s=at / float(self.flow_ul_s))  # type: ignore[arg-type]
        return replace(self, **{"volume_ul" if self.by_volume else "pressure_pa": at})

    def as_dict(self) -> dict[str, object]:
        return {"kind": self.kind, "pressure_pa": self.pressure_pa,
                "angle_deg": self.angle_deg, "force_mn": self.force_mn,
                "volume_ul": self.volume_ul, "time_s": self.time_s,
                "flow_ul_s": self.flow_ul_s}


def finite_number(v: object) -> bool:
    """A real number (int or float) that is finite."""
    return isinstance(v, (int, float)) and np.isfinite(v)


def _positive(v: float) -> bool:
    """More than 0, a subnormal magnitude (5e-324 ul, 1e-310 deg) counting as 0."""
    return v >= SMALLEST_NORMAL


def _got(v: object) -> str:
    """A target's value as a refusal quotes it: a subnormal one said to count as 0 (a
    pressure_pa of 5e-324 was refused as "got 5e-324 (allowed: 0 < pressure_pa ...)",
    a value its words allow)."""
    if v is None:
        return "none"
    subnormal = finite_number(v) and 0 < abs(v) < SMALLEST_NORMAL  # type: ignore[arg-type]
    return repr(v) + (f", below the smallest normal float ({SMALLEST_NORMAL:.3g}): counted "
                      "as 0" if subnormal else "")
