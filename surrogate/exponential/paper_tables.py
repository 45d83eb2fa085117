"""The reference paper's published model constants and fitted tables.

Source: "Characterization of bending balloon actuators" (the project's reference
paper): Table 3 (standard design), Table 4 (amplification constant A per chamber
length, tau fixed at 420), Table 5 (pressure constant tau per membrane thickness,
A fixed at 0.65), Eq. 5 (angle = A (exp(p / tau) - 1)) and Eq. 6 (tau = a_t ln(b_t t)
as printed). Values are copied as printed; units: angle in degrees, pressure in Pa,
lengths in mm (the reading confirmed in docs/surrogate.md).

The printed Eq. 6 uses the natural logarithm, but with the printed a_t and b_t
only the base-10 logarithm reproduces Table 5 (see ``tau_from_paper_constants``
and tests/test_surrogate_paper.py); the model in this package therefore uses
tau = a_t log10(b_t t).
"""

from __future__ import annotations

import math

SOURCE = "Characterization of bending balloon actuators (reference paper), Tables 3-5, Eqs. 5-6"

# Table 3: the standard design.
STANDARD_L_MM = 7.1
STANDARD_T_MM = 1.0
STANDARD_t_MM = 0.5
STANDARD_B_MM = 1.8
STANDARD_H_MM = 0.15  # chamber height 150 um (text)
STANDARD_BODY = "pdms_1_10"
STANDARD_MEMBRANE = "ecoflex_00_30"

# Table 4: A (deg) with tau fixed at 420 Pa; (L_mm, A, standard error, R^2).
TABLE_4_TAU_FIXED_PA = 420.0
TABLE_4 = (
    (4.1, 0.387, 0.014, 0.959),
    (7.1, 0.704, 0.007, 0.998),
    (11.1, 1.142, 0.016, 0.996),
    (15.1, 1.626, 0.032, 0.992),
)
# Slope of A against L (through the origin): a (deg/mm), its standard error, R^2.
A_DEG_PER_MM = 0.101
A_SE = 0.002
A_R2 = 0.991

# Table 5: tau (Pa) with A fixed at 0.65 deg; (t_mm, tau, standard error, R^2).
TABLE_5_A_FIXED_DEG = 0.65
TABLE_5 = (
    (0.5, 412.2, 0.902, 0.998),
    (0.75, 528.6, 1.07, 0.998),
    (1.0, 638.3, 1.17, 0.998),
)
# Eq. 6 constants as printed, with standard errors, R^2 = 0.988.
A_T_PA = 731.2
A_T_SE = 57.11
B_T_PER_MM = 7.179
B_T_SE = 0.896
TAU_R2 = 0.988

# Simulated grid (Table 2 notes): chamber lengths and membrane thicknesses.
SIMULATED_L_MM = (4.1, 5.1, 7.1, 9.1, 11.1, 13.1, 15.1, 17.1)
SIMULATED_t_MM = (0.25, 0.5, 0.75, 1.0)
TWO_BALLOON_BELOW_t_MM = 0.5  # "membranes thinner than 0.5 mm form two small balloons"


def tau_from_paper_constants(t_mm: float, log: str = "log10") -> float:
    """Eq. 6 with the printed constants, read with ``log`` = "log10" or "ln"."""
    fn = {"log10": math.log10, "ln": math.log}[log]
    return A_T_PA * fn(B_T_PER_MM * t_mm)
