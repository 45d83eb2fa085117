"""Validity of an answer: is the design and every pressure inside what the FE data covered?

Flags (each with a message):

    L_outside_fitted_range   chamber length outside the family's fitted L range
    t_outside_fitted_range   membrane thickness outside the fitted t range
    two_balloon_regime       t < 0.5 mm: the membrane forms two small balloons (paper)
    width_not_fitted         actuator width W not among the widths of the family's data
    pressure_beyond_fe       a pressure above the family's last converged FE point
    angle_beyond_fe          a predicted angle beyond the largest FE angle of the family
    past_fe_range            either of the two: the model gives no number there (NaN,
                             null over HTTP; ``past_fe``), as every Predictor does

``in_domain`` is about the design: True unless a flag about it is raised (the first four);
the flags about asked points (``surrogate.predictor.POINT_FLAGS``) keep their own flags.
"""

from __future__ import annotations

import numpy as np

from solver.design import Design
from surrogate.exponential.family import Domain
from surrogate.exponential.paper_tables import TWO_BALLOON_BELOW_t_MM
from surrogate.predictor import POINT_FLAGS

_TOL = 1e-9


def past_fe(domain: Domain, pressure_pa: np.ndarray, angle_deg: np.ndarray) -> np.ndarray:
    """Where an answer is past the family's FE range: a pressure above its last converged
    FE point, or an angle magnitude beyond its largest FE angle (the exponential form
    grows without bound there: 164 deg at 2500 Pa, 2e17 deg at 20 kPa)."""
    p = np.asarray(pressure_pa, dtype=float)
    a = np.abs(np.asarray(angle_deg, dtype=float))
    return ((p > domain.pressure_max_pa * (1 + _TOL))
            | (a > domain.angle_max_deg * (1 + _TOL)))


def check(domain: Domain, design: Design, pressure_pa: np.ndarray,
          angle_deg: np.ndarray) -> dict[str, object]:
    """Flags and messages for one design and its pressures / predicted angles."""
    flags: list[str] = []
    messages: list[str] = []
    (L0, L1), (t0, t1) = domain.L_mm, domain.t_mm
    if not L0 - _TOL <= design.L_mm <= L1 + _TOL:
        flags.append("L_outside_fitted_range")
        messages.append(f"L_mm = {design.L_mm:g} is outside the fitted range "
                        f"{L0:g}..{L1:g} mm: extrapolated")
    if not t0 - _TOL <= design.t_mm <= t1 + _TOL:
        flags.append("t_outside_fitted_range")
        messages.append(f"t_mm = {design.t_mm:g} is outside the fitted range "
                        f"{t0:g}..{t1:g} mm: extrapolated")
    if design.t_mm < TWO_BALLOON_BELOW_t_MM - _TOL:
        flags.append("two_balloon_regime")
        messages.append(f"t_mm = {design.t_mm:g} < {TWO_BALLOON_BELOW_t_MM} mm: the membrane "
                        "forms two small balloons, bends little and ruptures more easily")
    if domain.W_mm and not any(abs(design.W_mm - w) < 1e-6 for w in domain.W_mm):
        flags.append("width_not_fitted")
        messages.append(f"W_mm = {design.W_mm:g} differs from the fitted width(s) "
                        f"{', '.join(f'{w:g}' for w in domain.W_mm)} mm")
    p = np.asarray(pressure_pa, dtype=float)
    if p.size and float(np.nanmax(p)) > domain.pressure_max_pa * (1 + _TOL):
        n = int(np.sum(p > domain.pressure_max_pa))
        flags.append("pressure_beyond_fe")
        messages.append(f"{n} pressure(s) above {domain.pressure_max_pa:.0f} Pa, the family's "
                        "last converged FE point: no number is given there (null)")
    a = np.abs(np.asarray(angle_deg, dtype=float))
    if a.size and float(np.nanmax(a)) > domain.angle_max_deg * (1 + _TOL):
        flags.append("angle_beyond_fe")
        messages.append(f"angles beyond {domain.angle_max_deg:.1f} deg, the largest FE angle "
                        "of the family: no number is given there (null)")
    if past_fe(domain, p, angle_deg).any():
        flags.append("past_fe_range")  # the two above, under the name every model uses
        messages.append("no number is given past the FE's range (null there)")
    return {"in_domain": not [f for f in flags if f not in POINT_FLAGS],
            "flags": flags, "messages": messages,
            "L_range_mm": list(domain.L_mm), "t_range_mm": list(domain.t_mm),
            "pressure_max_pa": domain.pressure_max_pa, "angle_max_deg": domain.angle_max_deg,
            "fe_limit_pa": domain.pressure_max_pa, "fe_limit_angle_deg": domain.angle_max_deg}
