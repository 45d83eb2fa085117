"""Synthetic curve records for tests, benchmarks and demonstrations (no FE needed).

Curves follow the model exactly (``theta`` in ``surrogate.exponential.equations``'s
order) plus normal noise with the variance form of ``surrogate.exponential.bands``:
noise_deg^2 (1 - exp(-p/tau))^2 + (noise_rel angle)^2; each stops at ``max_angle_deg``
like an FE run with that stop criterion.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from solver.design import Design
from solver.materials import get_material
from surrogate.dataset import CurveData
from surrogate.exponential import bands, equations
from surrogate.exponential.paper_tables import A_DEG_PER_MM, A_T_PA, B_T_PER_MM

PAPER_THETA = np.array([A_DEG_PER_MM, A_T_PA, B_T_PER_MM])


def synthetic_curves(theta: np.ndarray = PAPER_THETA,
                     L_mm: tuple[float, ...] = (4.1, 7.1, 11.1, 15.1),
                     t_mm: tuple[float, ...] = (0.5, 0.75, 1.0),
                     body: str = "pdms_1_10", membrane: str = "ecoflex_00_30",
                     noise_deg: float = 0.0, noise_rel: float = 0.0, n_points: int = 25,
                     max_angle_deg: float = 90.0, force_theta: np.ndarray | None = None,
                     seed: int = 0, base: Design | None = None) -> list[CurveData]:
    """One free-tip curve per (L, t) (and a blocked-tip force curve per design when
    ``force_theta`` is given), pressures evenly spaced from 0 to where |angle| reaches
    ``max_angle_deg``."""
    rng = np.random.default_rng(seed)
    base = base or Design()
    out = []
    for L in L_mm:
        for t in t_mm:
            d = replace(base, L_mm=L, t_mm=t, body_material=get_material(body),
                        membrane_material=get_material(membrane))
            p_end = float(equations.pressure_pa(np.asarray(theta), L, t,
                                            np.sign(theta[0]) * max_angle_deg))
            p = np.linspace(0.0, p_end, n_points)
            y = equations.angle_deg(np.asarray(theta), L, t, p)
            x = p / equations.tau_pa(np.asarray(theta), t)
            y = y + rng.normal(size=p.shape) * np.sqrt(
                bands.scatter_variance(noise_deg, noise_rel, y, x))
            out.append(CurveData(d, p, y, np.full(p.shape, np.nan), key=f"syn-{L}-{t}"))
            if force_theta is not None:
                f = equations.angle_deg(np.asarray(force_theta), L, t, p)
                out.append(CurveData(d, p, np.zeros_like(p), f, key=f"synf-{L}-{t}",
                                     tip="blocked"))
    return out
