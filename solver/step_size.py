"""The size of the next load step: grown when Newton converged quickly, kept or shrunk
when it did not, and limited so that the curve is resolved where it changes fast.

The load increment is a cavity volume (mm^3, the model's own) under volume control and a
pressure (Pa) under pressure control. After each converged step the next is the last
times a factor: 1.6 after at most ``GROW_SOLVES`` Newton solves, 1.0 after at most
``HOLD_SOLVES``, 0.6 otherwise; no more than would give a bending increment of
``TARGET_ANGLE_STEP_DEG`` at the last step's rate, and under volume control no more than
would give a pressure increment of ``MAX_PRESSURE_STEP_PA`` (or
``MAX_RELATIVE_PRESSURE_STEP`` of the pressure, if more); neither limit shrinks a step
below half the last. A failed step is halved (the stepping, solver/stepping.py) down to
``MIN_CUTBACK`` of the first step.
"""

from __future__ import annotations

TARGET_ANGLE_STEP_DEG = 8.0
MAX_PRESSURE_STEP_PA = 150.0   # output resolution where the curve is steep in pressure,
MAX_RELATIVE_PRESSURE_STEP = 0.08   # or 8 % of the pressure when that is more (a blocked
                                    # tip climbing to kPa: ~45 steps to 20 kPa, not 130)
GROW_SOLVES = 4     # a step converged in at most this many Newton solves grows the next 1.6x,
HOLD_SOLVES = 7     # in at most this many keeps it, otherwise shrinks it to 0.6x (the
                    # Hermite predictor takes ~2 solves where the parabola took 3-4: these
                    # were 6 and 9 with the parabola)
MIN_CUTBACK = 1.0 / 1024.0
FIRST_STEP_SHARE = 0.05     # the first increment: this share of the chamber volume (mm^3),
                            # or of the softest material's shear modulus (Pa)


def first_step(volume_control: bool, volume0_mm3: float, mu0_min_pa: float) -> float:
    """The first load increment: a small fraction of the chamber volume (mm^3) under
    volume control, of the softest material's initial shear modulus (Pa) under pressure
    control."""
    return FIRST_STEP_SHARE * volume0_mm3 if volume_control else FIRST_STEP_SHARE * mu0_min_pa


def step_factor(newton_solves: int, angle_change_deg: float, pressure_change_pa: float,
                pressure_pa: float, volume_control: bool) -> float:
    """The next step over the last, from the last step's Newton solves and its changes of
    bending angle (deg, magnitude) and cavity pressure (Pa, magnitude) to the pressure
    ``pressure_pa``; the pressure limit applies under volume control only."""
    factor = 1.6 if newton_solves <= GROW_SOLVES else (
        1.0 if newton_solves <= HOLD_SOLVES else 0.6)
    if angle_change_deg > 1e-9:
        factor = min(factor, max(0.5, TARGET_ANGLE_STEP_DEG / angle_change_deg))
    if volume_control and pressure_change_pa > 1e-9:
        allowed = max(MAX_PRESSURE_STEP_PA, MAX_RELATIVE_PRESSURE_STEP * abs(pressure_pa))
        factor = min(factor, max(0.5, allowed / pressure_change_pa))
    return factor
