"""The catalogue of effects the calibration tests: one object per effect, one file each.

``CATALOGUE`` lists them in the order they are reported; ``EFFECTS`` by id. Each is an
``Effect`` (effects/_base.py): parameters with units, bounds, plausible range and null
value, the stage it acts on and its forward transform, when the data can identify it,
and the sentence that interprets it.
"""

from __future__ import annotations

from surrogate.calibration.effects import (
    angle_offset,
    body_stiffness,
    camera_gain,
    chamber_leak,
    chamber_length,
    gauge_drift,
    hydraulic_resistance,
    line_compliance,
    membrane_stiffness,
    membrane_thickness,
    pressure_gain,
    pressure_offset,
    pressure_relaxation,
    viscoelastic_creep,
)
from surrogate.calibration.effects._base import STAGES, DataTraits, Effect, EffectParameter
from surrogate.calibration.effects.hydraulic_resistance import (
    R_CHANNEL,
    rectangular_channel_resistance_pa_per_ul_s,
    round_tube_resistance_pa_per_ul_s,
)

CATALOGUE: tuple[Effect, ...] = (
    membrane_stiffness.EFFECT, body_stiffness.EFFECT, membrane_thickness.EFFECT,
    chamber_length.EFFECT, pressure_offset.EFFECT, pressure_gain.EFFECT,
    hydraulic_resistance.EFFECT, line_compliance.EFFECT, angle_offset.EFFECT,
    camera_gain.EFFECT,
    viscoelastic_creep.EFFECT, pressure_relaxation.EFFECT, chamber_leak.EFFECT,
    gauge_drift.EFFECT,
)
EFFECTS = {e.id: e for e in CATALOGUE}
EFFECT_IDS = tuple(EFFECTS)


def catalogue_dicts() -> list[dict[str, object]]:
    """The catalogue as plain data (GET /v1/effects)."""
    return [e.as_dict() for e in CATALOGUE]


__all__ = ["CATALOGUE", "EFFECTS", "EFFECT_IDS", "R_CHANNEL", "STAGES", "DataTraits", "Effect",
           "EffectParameter", "catalogue_dicts", "rectangular_channel_resistance_pa_per_ul_s",
           "round_tube_resistance_pa_per_ul_s"]
