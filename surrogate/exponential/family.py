"""A fitted family: the designs the exponential model does not parametrise (material
pair, body thickness T, chamber width b and height h), its parameters per model form,
an optional force model, and the domain its data covered."""

from __future__ import annotations

from dataclasses import dataclass

from solver.design import Design
from solver.materials import OgdenMaterial
from surrogate.exponential.parameters import (
    COVARIANCE_IN_LOG10_B_T_SINCE,
    ModelParameters,
    parameters_from_dict,
)
from surrogate.exponential.volume_relation import VolumeRelation, volume_relation_from_dict


@dataclass(frozen=True)
class Domain:
    """What the family's FE data covered: L and t ranges (mm), the largest pressure of a
    converged point (Pa) and the largest angle magnitude (deg), the actuator widths W
    (mm) and the (L, t) of every design used."""

    L_mm: tuple[float, float]
    t_mm: tuple[float, float]
    pressure_max_pa: float
    angle_max_deg: float
    W_mm: tuple[float, ...] = ()
    designs: tuple[tuple[float, float], ...] = ()
    notes: str = ""

    def as_dict(self) -> dict[str, object]:
        return {"L_mm": list(self.L_mm), "t_mm": list(self.t_mm),
                "pressure_max_pa": self.pressure_max_pa, "angle_max_deg": self.angle_max_deg,
                "W_mm": list(self.W_mm), "designs": [list(d) for d in self.designs],
                "n_designs": len(self.designs), "notes": self.notes}


def domain_from_dict(d: dict) -> Domain:
    return Domain(L_mm=tuple(d["L_mm"]), t_mm=tuple(d["t_mm"]),
                  pressure_max_pa=float(d["pressure_max_pa"]),
                  angle_max_deg=float(d["angle_max_deg"]), W_mm=tuple(d.get("W_mm", ())),
                  designs=tuple(tuple(x) for x in d.get("designs", ())),
                  notes=d.get("notes", ""))


@dataclass(frozen=True)
class Family:
    """``parameters`` maps a form name ("exponential", "extended") to its parameters;
    ``default_form`` is the one used unless a form is asked for; ``force`` is the force
    model (exponential form, mN) or None when the data held no force curves; ``volume``
    the pressure-volume relation (``volume_relation``) or None (the paper preset, files
    of format version < 3, curves without volumes)."""

    body_material: OgdenMaterial
    membrane_material: OgdenMaterial
    T_mm: float
    b_mm: float
    h_mm: float
    parameters: dict[str, ModelParameters]
    default_form: str
    domain: Domain
    force: ModelParameters | None = None
    volume: VolumeRelation | None = None

    @property
    def key(self) -> tuple[str, str, float, float, float]:
        return (self.body_material.id, self.membrane_material.id, round(self.T_mm, 6),
                round(self.b_mm, 6), round(self.h_mm, 6))

    @property
    def label(self) -> str:
        return (f"{self.body_material.id}/{self.membrane_material.id} T={self.T_mm:g} "
                f"b={self.b_mm:g} h={self.h_mm:g}")

    def matches(self, design: Design) -> bool:
        return (design.family == self.key and design.body_material == self.body_material
                and design.membrane_material == self.membrane_material)

    def as_dict(self) -> dict[str, object]:
        return {"body_material": self.body_material.as_dict(),
                "membrane_material": self.membrane_material.as_dict(),
                "T_mm": self.T_mm, "b_mm": self.b_mm, "h_mm": self.h_mm,
                "default_form": self.default_form,
                "parameters": {k: v.as_dict() for k, v in self.parameters.items()},
                "force": self.force.as_dict() if self.force else None,
                "domain": self.domain.as_dict(),
                "volume": self.volume.as_dict() if self.volume else None}


def _material(d: dict) -> OgdenMaterial:
    return OgdenMaterial(str(d["id"]), tuple(float(v) for v in d["mu_kpa"]),
                         tuple(float(v) for v in d["alpha"]))


def family_from_dict(d: dict, format_version: int = COVARIANCE_IN_LOG10_B_T_SINCE) -> Family:
    """From ``as_dict``; ``format_version`` of the file it was read from."""
    v = format_version
    return Family(body_material=_material(d["body_material"]),
                  membrane_material=_material(d["membrane_material"]),
                  T_mm=float(d["T_mm"]), b_mm=float(d["b_mm"]), h_mm=float(d["h_mm"]),
                  parameters={k: parameters_from_dict(p, v) for k, p in d["parameters"].items()},
                  default_form=d["default_form"], domain=domain_from_dict(d["domain"]),
                  force=parameters_from_dict(d["force"], v) if d.get("force") else None,
                  volume=volume_relation_from_dict(d["volume"]) if d.get("volume") else None)
