"""A layer's material with its stiffness scaled: the design change of a stiffer or softer
silicone batch (mixing ratio, cure), used by the stiffness effects and the test data."""

from __future__ import annotations

from solver.materials import OgdenMaterial


def scaled_material(material: OgdenMaterial, scale: float) -> OgdenMaterial:
    """``material`` with every mu_p x ``scale`` (same alpha and id): all its moduli, and
    so its initial shear modulus, x scale."""
    if scale == 1.0:
        return material
    return OgdenMaterial(material.id, tuple(scale * m for m in material.mu_kpa),
                         material.alpha)
