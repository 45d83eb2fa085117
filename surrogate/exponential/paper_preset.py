"""The ``paper`` preset: the reference paper's published constants as a surrogate.

One family (PDMS 1:10 body, Ecoflex 00-30 membrane, T = 1, b = 1.8, h = 0.15 mm), the
exponential form with a = 0.101 deg/mm, a_t = 731.2 Pa, b_t = 7.179 1/mm and
tau = a_t log10(b_t t) (the reading that reproduces Table 5; see docs/surrogate.md).

Uncertainty: standard errors as printed (a 0.002, a_t 57.11, b_t 0.896). The paper gives
no correlation; a_t and b_t come from one fit of tau against t, so their correlation is
taken from refitting Table 5 (``_tau_correlation``). Like a fitted one, the covariance
is stored in log10 b_t (``equations.covariance_from_b_t``: the same bands). Residual scatter
(its large-pressure level): sqrt(1 - R^2) times the spread of the standard design's
curve from 0 to 90 deg, with R^2 = 0.998 (Table 4, L = 7.1 mm). Domain: L and t of
Tables 4 and 5; the pressure and angle limits (3000 Pa, 90 deg) are assumptions (the
paper prints no axis limits).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from solver.materials import get_material
from surrogate.exponential import equations, paper_tables
from surrogate.exponential.family import Domain, Family
from surrogate.exponential.file import FORMAT_VERSION
from surrogate.exponential.parameters import ModelParameters
from surrogate.exponential.surrogate import Surrogate

PAPER_PRESSURE_MAX_PA = 3000.0
PAPER_ANGLE_MAX_DEG = 90.0


def _tau_correlation() -> float:
    """Correlation of (a_t, b_t) in the least-squares fit of Table 5's tau against t."""
    t = np.array([row[0] for row in paper_tables.TABLE_5])
    x = np.log10(t)
    X = np.column_stack([x, np.ones_like(x)])
    cov_lin = np.linalg.inv(X.T @ X)  # up to the residual variance, which cancels
    a_t, b_t = paper_tables.A_T_PA, paper_tables.B_T_PER_MM
    icept = a_t * math.log10(b_t)
    J = np.array([[1.0, 0.0],
                  [-b_t * math.log(10) * icept / a_t**2, b_t * math.log(10) / a_t]])
    cov = J @ cov_lin @ J.T
    return float(cov[0, 1] / math.sqrt(cov[0, 0] * cov[1, 1]))


def _residual_sd_deg(theta: np.ndarray) -> float:
    L, t = paper_tables.STANDARD_L_MM, paper_tables.STANDARD_t_MM
    p90 = float(equations.pressure_pa(theta, L, t, PAPER_ANGLE_MAX_DEG))
    curve = equations.angle_deg(theta, L, t, np.linspace(0.0, p90, 201))
    r2 = [row[3] for row in paper_tables.TABLE_4 if row[0] == L][0]
    return float(math.sqrt(1.0 - r2) * np.std(curve))


@lru_cache(maxsize=1)
def paper_surrogate() -> Surrogate:
    """The paper's model with its printed constants, named "paper"."""
    theta = np.array([paper_tables.A_DEG_PER_MM, paper_tables.A_T_PA, paper_tables.B_T_PER_MM])
    se = np.array([paper_tables.A_SE, paper_tables.A_T_SE, paper_tables.B_T_SE])
    corr = np.eye(3)
    corr[1, 2] = corr[2, 1] = _tau_correlation()
    cov = equations.covariance_from_b_t(corr * np.outer(se, se), theta)
    params = ModelParameters(
        form="exponential", names=equations.PARAMETER_NAMES["exponential"],
        values=tuple(float(v) for v in theta),
        covariance=tuple(tuple(float(v) for v in r) for r in cov),
        residual_sd=_residual_sd_deg(theta), residual_rel=0.0, source="paper",
        extra={"tau_reading": "log10 (printed Eq. 6 says ln; only log10 reproduces Table 5)"})
    L = [row[0] for row in paper_tables.TABLE_4]
    t = [row[0] for row in paper_tables.TABLE_5]
    domain = Domain(
        L_mm=(min(L), max(L)), t_mm=(min(t), max(t)), pressure_max_pa=PAPER_PRESSURE_MAX_PA,
        angle_max_deg=PAPER_ANGLE_MAX_DEG, W_mm=(3.0,),
        designs=tuple((x, paper_tables.STANDARD_t_MM) for x in L)
        + tuple((paper_tables.STANDARD_L_MM, x) for x in t if x != paper_tables.STANDARD_t_MM),
        notes="L and t from Tables 4-5; pressure and angle limits assumed (not printed)")
    family = Family(body_material=get_material(paper_tables.STANDARD_BODY),
                    membrane_material=get_material(paper_tables.STANDARD_MEMBRANE),
                    T_mm=paper_tables.STANDARD_T_MM, b_mm=paper_tables.STANDARD_B_MM,
                    h_mm=paper_tables.STANDARD_H_MM, parameters={"exponential": params},
                    default_form="exponential", domain=domain)
    return Surrogate(name="paper", family_fits=(family,),
                     provenance={"source": paper_tables.SOURCE,
                                 "format_version": FORMAT_VERSION})
