"""A layer's material with its stiffness scaled: the design change of a stiffer or softer
silicone batch (mixing ratio, cure), as the design space defines it
(``solver.design_space``: a preset with every mu_kpa x s, id ``preset*s``)."""

from __future__ import annotations

from solver.design_space import recognise, scaled_material
from solver.materials import OgdenMaterial, make_material


def scale_layer(material: OgdenMaterial, scale: float) -> OgdenMaterial:
    """``material`` with every mu_p x ``scale`` (same alpha): a preset scaled by s0
    becomes the preset scaled by s0 x scale; any other material keeps its id."""
    if scale == 1.0:
        return material
    found = recognise(material)
    if found is not None:
        return scaled_material(found[0], found[1] * scale)
    return make_material(material.id, [scale * m for m in material.mu_kpa],
                         list(material.alpha))
