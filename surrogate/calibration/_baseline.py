"""The calibration's baseline parameters: one family's exponential-model constants.

The equations are ``surrogate.exponential.equations`` (angle = A (exp(x + c x^2) - 1),
x = p / tau, A = a L, tau = a_t log10(b_t t)); c = 0 is the paper's Eq. 5 (calibration
keeps c at the starting model's value). The paper's constants are
``surrogate.exponential.paper_tables``; why log10 and not the printed ln: see there.
"""

from __future__ import annotations

from dataclasses import dataclass

from surrogate.exponential.paper_tables import A_DEG_PER_MM, A_T_PA, B_T_PER_MM


@dataclass(frozen=True)
class FamilyParameters:
    """One family's exponential-model parameters (family = body material, membrane
    material, T_mm, b_mm, h_mm)."""

    a_deg_per_mm: float
    a_t_pa: float
    b_t_per_mm: float
    c: float = 0.0

    def as_dict(self) -> dict[str, float]:
        return {"a_deg_per_mm": self.a_deg_per_mm, "a_t_pa": self.a_t_pa,
                "b_t_per_mm": self.b_t_per_mm, "c": self.c}


PAPER_PARAMETERS = FamilyParameters(A_DEG_PER_MM, A_T_PA, B_T_PER_MM)
