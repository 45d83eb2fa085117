"""The paper's two-stage procedure on one family (analogues of its Tables 4 and 5).

Reference design: the standard (L = 7.1, t = 0.5 mm) when the family has it, else the
design nearest to it. Its free fit gives tau_ref and A_ref (the paper's 420 and 0.65).
Every curve is fitted three ways (free, tau = tau_ref, A = A_ref). Table 4 analogue: the
curves at t = t_ref, A (tau fixed) against L, slope a through the origin. Table 5
analogue: the curves at L = L_ref, tau (A fixed) against t, tau = a_t log10(b_t t).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from surrogate.exponential.family_fit import Points
from surrogate.exponential.paper_tables import STANDARD_L_MM, STANDARD_t_MM
from surrogate.exponential.per_curve_fits import (
    fit_A_fixed,
    fit_free,
    fit_tau_fixed,
    length_constant,
    thickness_constants,
)


def paper_procedure(pts: Points) -> dict[str, object]:
    """Per-curve fits and the Tables 4-5 analogues, as plain JSON."""
    curves = []
    for i in np.unique(pts.curve):
        sub = pts.subset(pts.curve == i)
        curves.append((float(sub.L_mm[0]), float(sub.t_mm[0]), sub))
    L_all = np.array([c[0] for c in curves])
    t_all = np.array([c[1] for c in curves])
    dist = ((L_all - STANDARD_L_MM) / STANDARD_L_MM) ** 2 + ((t_all - STANDARD_t_MM)
                                                              / STANDARD_t_MM) ** 2
    ref = int(np.argmin(dist))
    L_ref, t_ref = curves[ref][0], curves[ref][1]
    ref_fit = fit_free(curves[ref][2].pressure_pa, curves[ref][2].value)
    rows: list[dict[str, Any]] = []
    for L, t, sub in curves:
        p, y = sub.pressure_pa, sub.value
        rows.append({"L_mm": L, "t_mm": t, "free": fit_free(p, y).as_dict(),
                     "tau_fixed": fit_tau_fixed(p, y, ref_fit.tau_pa).as_dict(),
                     "A_fixed": fit_A_fixed(p, y, ref_fit.A_deg).as_dict()})
    l_series = [r for r in rows if abs(r["t_mm"] - t_ref) < 1e-9]
    t_series = [r for r in rows if abs(r["L_mm"] - L_ref) < 1e-9]
    table_4: dict[str, Any] = {"t_mm": t_ref, "tau_fixed_pa": ref_fit.tau_pa,
               "rows": [{"L_mm": r["L_mm"], **_pick(r["tau_fixed"], "A")} for r in l_series]}
    if l_series:
        line = length_constant(np.array([r["L_mm"] for r in l_series]),
                               np.array([r["tau_fixed"]["A_deg"] for r in l_series]))
        table_4["length_constant"] = line.as_dict()
    table_5: dict[str, Any] = {"L_mm": L_ref, "A_fixed_deg": ref_fit.A_deg,
               "rows": [{"t_mm": r["t_mm"], **_pick(r["A_fixed"], "tau")} for r in t_series]}
    if len({r["t_mm"] for r in t_series}) >= 2:
        line = thickness_constants(np.array([r["t_mm"] for r in t_series]),
                                   np.array([r["A_fixed"]["tau_pa"] for r in t_series]))
        table_5["thickness_constants"] = line.as_dict()
    return {"reference_design": {"L_mm": L_ref, "t_mm": t_ref, "free_fit": ref_fit.as_dict()},
            "table_4": table_4, "table_5": table_5, "curve_fits": rows}


def _pick(fit: dict, name: str) -> dict:
    key = "A_deg" if name == "A" else "tau_pa"
    return {key: fit[key], f"{name}_se": fit[f"{name}_se"], "r2": fit["r2"]}
