"""What a design search answers: the ranked designs (``DesignCandidate``) or why none
(``InverseDesignResult``), as plain dicts for the HTTP and CLI shells (``as_dict``).

Pressures in Pa, angles in deg, forces in mN, injected volumes in ul, times in s; a
candidate's curve is the model's ``Prediction`` from 0 to the target.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from solver.design import Design
from surrogate.predictor import Prediction
from surrogate.search.design_target import DesignTarget

#: what a listed design reports for a syringe pump's target (DesignCandidate)
PUMP_FIELDS = ("volume_needed_ul", "volume_lower_ul", "volume_upper_ul", "time_needed_s",
               "time_lower_s", "time_upper_s", "angle_at_volume_deg",
               "angle_at_volume_lower_deg", "angle_at_volume_upper_deg",
               "pressure_at_volume_pa")
@dataclass(frozen=True)
class DesignCandidate:
    """A ranked design: the score of the objective (lower is better), the pressure it
    needs (pressure_budget) or its predicted value at the target pressure, and the
    predicted curve from 0 Pa with its band."""

    rank: int
    design: Design
    family: str
    score: float
    pressure_needed_pa: float
    pressure_lower_pa: float
    pressure_upper_pa: float
    value_at_pressure: float
    value_lower: float
    value_upper: float
    curve: Prediction
    # the value's change (deg or mN) when one length is made 0.01 mm larger, the others
    # kept: a mould's tolerance read on the answer (design-space search; None otherwise)
    change_per_0_01_mm: dict[str, float] | None = None
    # a syringe pump's target (surrogate.search.pump_targets.volume_report; None otherwise): the
    # injected volume needed for the angle with its band (ul), the time at the target's
    # flow rate (s), and at the target volume the angle with its band (deg) and the
    # chamber pressure (Pa)
    volume_needed_ul: float | None = None
    volume_lower_ul: float | None = None
    volume_upper_ul: float | None = None
    time_needed_s: float | None = None
    time_lower_s: float | None = None
    time_upper_s: float | None = None
    angle_at_volume_deg: float | None = None
    angle_at_volume_lower_deg: float | None = None
    angle_at_volume_upper_deg: float | None = None
    pressure_at_volume_pa: float | None = None

    def as_dict(self) -> dict[str, object]:
        from solver.design_space import recognise

        def preset_and_scale(material: object) -> tuple[str, float]:
            found = recognise(material)  # type: ignore[arg-type]
            return found if found is not None else (material.id, 1.0)  # type: ignore

        body, s_body = preset_and_scale(self.design.body_material)
        membrane, s_membrane = preset_and_scale(self.design.membrane_material)
        return {"rank": self.rank, "L_mm": self.design.L_mm, "t_mm": self.design.t_mm,
                "T_mm": self.design.T_mm, "b_mm": self.design.b_mm, "h_mm": self.design.h_mm,
                "body_material": body, "membrane_material": membrane,
                "body_stiffness_scale": s_body, "membrane_stiffness_scale": s_membrane,
                "design": self.design.as_dict(),
                "family": self.family, "score": self.score,
                "pressure_needed_pa": self.pressure_needed_pa,
                "pressure_lower_pa": self.pressure_lower_pa,
                "pressure_upper_pa": self.pressure_upper_pa,
                "value_at_pressure": self.value_at_pressure, "value_lower": self.value_lower,
                "value_upper": self.value_upper,
                "change_per_0_01_mm": self.change_per_0_01_mm,
                **{name: getattr(self, name) for name in PUMP_FIELDS},
                "validity": self.curve.validity,
                "curve": {k: v for k, v in self.curve.as_dict().items()
                          if k in ("pressure_pa", "angle_deg", "lower_deg", "upper_deg",
                                   "force_mn", "force_lower_mn", "force_upper_mn",
                                   "volume_ul")}}


@dataclass(frozen=True)
class InverseDesignResult:
    """Ranked feasible designs, or an explanation (``feasible`` False) with the largest
    value reachable at the target pressure inside the bounds (``best_reachable``)."""

    target: DesignTarget
    objective: str
    feasible: bool
    candidates: tuple[DesignCandidate, ...]
    explanation: str
    best_reachable: dict = field(default_factory=dict)
    n_evaluated: int = 0
    model: str = ""

    def as_dict(self) -> dict[str, object]:
        return {"target": self.target.as_dict(),
                "objective": self.objective, "feasible": self.feasible,
                "candidates": [c.as_dict() for c in self.candidates],
                "explanation": self.explanation, "best_reachable": dict(self.best_reachable),
                "n_evaluated": self.n_evaluated, "model": self.model}
