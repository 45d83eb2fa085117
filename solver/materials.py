"""Ogden hyperelastic materials: the paper's presets and validated custom ones.

Strain energy per reference volume (isochoric part, on the isochoric principal
stretches lbar_i = J^(-1/3) lambda_i)::

    W_iso = sum_p mu_p / alpha_p * (lbar_1^alpha_p + lbar_2^alpha_p + lbar_3^alpha_p - 3)

Initial shear modulus ``mu0 = sum_p mu_p * alpha_p / 2``.

Units: the paper's Table 1 prints mu_p in kPa. We keep kPa in the material
definitions (``mu_kpa``) and work in Pa inside the solver (``mu_pa``). With
lengths in mm and pressures in Pa this reading reproduces the paper's
pressure scale (angle = 0.704 (exp(p/420) - 1) with p in Pa); see
docs/physics.md. Terms with alpha = 0 or mu = 0 carry no energy under this form
(mu/alpha is undefined or zero) and are dropped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from solver.errors import InputError, NotFoundError
from solver.ogden_paths import STABLE_STRETCH_MAX, unstable_at

# A material's id: a name, or a preset scaled as solver.design_space.scaled_material names
# it (``ecoflex_00_30*1.5``); never a path, never a control character. The service's
# schemas take ids by it, and a grid's custom materials are held to it.
MATERIAL_ID_PATTERN = r"^[A-Za-z0-9_][A-Za-z0-9_.\-]{0,63}(\*[0-9][0-9.eE+\-]{0,15})?$"
MATERIAL_ID_WORDS = ("1-64 letters, digits, '_', '.', '-', not starting with '.' or '-' "
                     "(a scaled preset: <preset>*<scale>)")


# The softest initial shear modulus mu0 a material may have, kPa: the softest layer the
# box allows is Ecoflex 00-30 (mu0 = 1.88 kPa, Table 1 below) scaled by the smallest
# stiffness scale 0.01 (solver.design_space.STIFFNESS_SCALE_LIMITS), 0.019 kPa; 1e-3 kPa
# (1 Pa, a gel far softer than any silicone) leaves a margin of 19 below it. A membrane of
# mu = 1e-300 kPa was solved for 32 s to a curve that failed at rest
# (tests/test_hostile_s44.py checks the floor against the box).
MIN_MU0_KPA = 1e-3


@dataclass(frozen=True)
class OgdenMaterial:
    """An N-term Ogden material. ``mu_kpa`` and ``alpha`` have equal length >= 1."""

    id: str
    mu_kpa: tuple[float, ...]
    alpha: tuple[float, ...]

    @property
    def mu0_kpa(self) -> float:
        """Initial (small-strain) shear modulus in kPa."""
        return sum(m * a for m, a in zip(self.mu_kpa, self.alpha)) / 2.0

    @property
    def mu_pa(self) -> tuple[float, ...]:
        return tuple(1e3 * m for m in self.mu_kpa)

    def as_dict(self) -> dict[str, object]:
        return {"id": self.id, "mu_kpa": list(self.mu_kpa), "alpha": list(self.alpha)}


#: an Ogden term's limits (each of 1 to 6 terms), and in words
MAX_MU_KPA = 1e6
MAX_ALPHA = 50.0
TERM_WORDS = f"|mu| <= 1e{math.log10(MAX_MU_KPA):.0f} kPa, |alpha| <= {MAX_ALPHA:g}"


def make_material(material_id: str, mu_kpa: list[float] | tuple[float, ...],
                  alpha: list[float] | tuple[float, ...]) -> OgdenMaterial:
    """Validate Ogden parameters and drop the terms that carry no energy.

    Raises InputError when the lists differ in length, hold non-finite values,
    when the initial shear modulus is below MIN_MU0_KPA (not positive: the material
    would have no stiffness in the undeformed state), or when the material is unstable
    within the FE's stretches (solver.ogden_paths: the stress falls with stretch).
    A material read back from a database is not checked again (``stored_material``).
    """
    mu = [float(m) for m in mu_kpa]
    al = [float(a) for a in alpha]
    if len(mu) != len(al) or not mu:
        raise InputError("mu_kpa", "mu_kpa and alpha must be non-empty lists of equal length",
                         "1 to 6 terms")
    if len(mu) > 6:
        raise InputError("mu_kpa", f"{len(mu)} Ogden terms given", "1 to 6 terms")
    for name, values in (("mu_kpa", mu), ("alpha", al)):
        for v in values:
            if v != v or abs(v) == float("inf"):
                raise InputError(name, "values must be finite numbers")
    for m, a in zip(mu, al):
        if abs(m) > MAX_MU_KPA or abs(a) > MAX_ALPHA:
            raise InputError("mu_kpa", f"term (mu={m} kPa, alpha={a}) is out of range",
                             TERM_WORDS)
    kept = [(m, a) for m, a in zip(mu, al) if m != 0.0 and a != 0.0]
    if not kept:
        raise InputError("mu_kpa", "every Ogden term has mu = 0 or alpha = 0",
                         "at least one term with mu != 0 and alpha != 0")
    material = OgdenMaterial(material_id, tuple(m for m, _ in kept), tuple(a for _, a in kept))
    if not material.mu0_kpa >= MIN_MU0_KPA:
        raise InputError("mu_kpa", f"initial shear modulus sum(mu*alpha)/2 = "
                         f"{material.mu0_kpa:.4g} kPa is "
                         + ("not positive" if material.mu0_kpa <= 0 else
                            "softer than any material the FE is meant for"),
                         f"mu0 = sum(mu*alpha)/2 >= {MIN_MU0_KPA:g} kPa")
    unstable = unstable_at(material.mu_kpa, material.alpha)
    if unstable is not None:
        path, stretch = unstable
        raise InputError("mu_kpa", f"the Ogden terms make an unstable material: its "
                         f"{path} stress falls with stretch at a stretch of {stretch:.3g} "
                         f"({'tension' if stretch > 1 else 'compression'})",
                         f"a stable material: stress rising with stretch in uniaxial, planar "
                         f"and equibiaxial tension and compression up to a stretch of "
                         f"{STABLE_STRETCH_MAX:g} (every term with mu*alpha > 0 and alpha >= 1 or "
                         f"alpha <= -2 is)")
    return material


def stored_material(material_id: str, mu_kpa: object, alpha: object) -> OgdenMaterial:
    """A material as a database record stores it, read as written: ``make_material``'s
    checks are for new input, and a record stored before one of them existed (the mu0
    floor and the stability check, 2026-12-07) stays readable, not "damaged"."""
    return OgdenMaterial(str(material_id), tuple(float(m) for m in mu_kpa),  # type: ignore[attr-defined]
                         tuple(float(a) for a in alpha))  # type: ignore[attr-defined]


# Table 1 of the paper, as printed (kPa). make_material drops the alpha = 0 term of
# PDMS 1:10 and the mu = 0 term of PDMS 1:15.
PAPER_TABLE_1: dict[str, tuple[tuple[float, float], tuple[float, float]]] = {
    "ecoflex_00_30": ((1.241, 7.879e-9), (3.034, 13.02)),
    "pdms_1_10": ((1.111e-22, 21.66), (0.0, 3.268)),
    "pdms_1_15": ((0.0, 9.417), (1.176, 3.299)),
}

MATERIALS: dict[str, OgdenMaterial] = {
    name: make_material(name, mu, alpha) for name, (mu, alpha) in PAPER_TABLE_1.items()
}


def get_material(material_id: str) -> OgdenMaterial:
    """Look up a preset by id; raises NotFoundError naming the known ids."""
    try:
        return MATERIALS[material_id]
    except KeyError:
        raise NotFoundError(f"unknown material {material_id!r}; known: "
                            f"{', '.join(sorted(MATERIALS))}") from None
