"""The actuator's design: geometry (mm) and the two layers' materials.

Coordinates (mm): x along the length from the clamped end (x = 0), y across the
width (the model uses the half y >= 0, y = 0 being the symmetry plane), z up.
Membrane B occupies 0 <= z <= t; body A sits on it, t <= z <= t + h + T, with
the chamber (L x b x h) moulded in its underside, t <= z <= t + h,
|y| <= b/2, offset <= x <= offset + L.

Defaults are the paper's standard design (Table 3): L = 7.1, t = 0.5, T = 1,
b = 1.8, h = 0.15, W = 3, PDMS 1:10 body, Ecoflex 00-30 membrane.

Body length: 12 mm (the paper's), grown to L + 2 x 1 mm when the chamber and a
1 mm wall at each end would not fit; both lengths are the paper's at its width W = 3 mm
and scale with W (max(12, L + 2) x W / 3 in the W = 3 mm design's terms), so that the
default design at any width is a scaled copy of one at 3 mm (scaling every length
leaves angle(p) unchanged: docs/physics.md). Chamber position: centred along the body
unless ``chamber_offset_mm`` is given (distance from the clamped end to the
chamber's start).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from solver.errors import InputError
from solver.materials import MATERIALS, OgdenMaterial
from solver.number_text import WrittenNumber

PAPER_WIDTH_MM = 3.0               # the standard design's W (Table 3)
DEFAULT_BODY_LENGTH_MM = 12.0      # at PAPER_WIDTH_MM; scaled with W
END_WALL_MM = 1.0                  # at PAPER_WIDTH_MM; scaled with W

# (min, max) for every length, in mm; checked by Design.validated().
LIMITS_MM: dict[str, tuple[float, float]] = {
    "L_mm": (0.5, 60.0),
    "t_mm": (0.05, 5.0),
    "T_mm": (0.1, 10.0),
    "b_mm": (0.1, 20.0),
    "h_mm": (0.02, 5.0),
    "W_mm": (0.2, 30.0),
    "body_length_mm": (0.5, 200.0),   # the default body at W 0.2 mm (0.8) and at 30 (120)
    "chamber_offset_mm": (0.1, 100.0),
}


@dataclass(frozen=True)
class Design:
    """A bending balloon actuator. Use ``Design(...).validated()`` on user input."""

    L_mm: float = 7.1
    t_mm: float = 0.5
    T_mm: float = 1.0
    b_mm: float = 1.8
    h_mm: float = 0.15
    W_mm: float = PAPER_WIDTH_MM
    body_length_mm: float | None = None
    chamber_offset_mm: float | None = None
    body_material: OgdenMaterial = field(default_factory=lambda: MATERIALS["pdms_1_10"])
    membrane_material: OgdenMaterial = field(
        default_factory=lambda: MATERIALS["ecoflex_00_30"])

    def __post_init__(self) -> None:
        """Either material may also be given as a preset id (``Design(body_material=
        "pdms_1_15")``) or as ``{"id", "mu_kpa", "alpha"}``; anything else is an
        InputError naming the field and the preset ids."""
        for name in ("body_material", "membrane_material"):
            value = getattr(self, name)
            if not isinstance(value, OgdenMaterial):
                object.__setattr__(self, name, material_from_input(value, name))

    @property
    def resolved_body_length_mm(self) -> float:
        if self.body_length_mm is not None:
            return float(self.body_length_mm)
        k = self.W_mm / PAPER_WIDTH_MM
        return max(k * DEFAULT_BODY_LENGTH_MM, self.L_mm + 2 * k * END_WALL_MM)

    @property
    def resolved_chamber_offset_mm(self) -> float:
        if self.chamber_offset_mm is not None:
            return float(self.chamber_offset_mm)
        return 0.5 * (self.resolved_body_length_mm - self.L_mm)

    @property
    def family(self) -> tuple[str, str, float, float, float]:
        """What the paper's exponential model does not parametrise."""
        return (self.body_material.id, self.membrane_material.id,
                round(self.T_mm, 6), round(self.b_mm, 6), round(self.h_mm, 6))

    def validated(self) -> Design:
        """Check ranges and consistency; return the design with lengths resolved."""
        values = {name: getattr(self, name) for name in LIMITS_MM}
        for name, value in values.items():
            if value is None:
                continue
            lo, hi = LIMITS_MM[name]
            if not isinstance(value, (int, float)) or value != value or not lo <= value <= hi:
                raise InputError(name, f"got {value!r}", f"{lo} <= {name} <= {hi}")
        if self.b_mm >= self.W_mm:
            raise InputError("b_mm", f"chamber width {self.b_mm} mm does not fit in the "
                             f"actuator width {self.W_mm} mm", f"b_mm < W_mm = {self.W_mm}")
        body = self.resolved_body_length_mm
        if body < self.L_mm + 0.2 - 1e-9:     # no chamber offset could fit it
            raise InputError("body_length_mm", f"a body of {body:g} mm cannot hold a "
                             f"chamber of L_mm = {self.L_mm:g} mm and its end walls",
                             f"body_length_mm >= L_mm + 0.2 = {self.L_mm + 0.2:g}")
        offset = self.resolved_chamber_offset_mm
        if offset + self.L_mm > body - 0.1 or offset < 0.1:
            raise InputError("chamber_offset_mm", f"chamber from x = {offset:g} to "
                             f"{offset + self.L_mm:g} mm does not fit in a body of {body:g} mm",
                             f"0.1 <= chamber_offset_mm <= {body - self.L_mm - 0.1:g}")
        if (type(self.body_length_mm) is float and type(self.chamber_offset_mm) is float
                and self.body_length_mm == body and self.chamber_offset_mm == offset):
            return self             # already resolved: a query validates its design twice
        return replace(self, body_length_mm=body, chamber_offset_mm=offset)

    def as_dict(self) -> dict[str, object]:
        d = self.validated()
        return {
            "L_mm": d.L_mm, "t_mm": d.t_mm, "T_mm": d.T_mm, "b_mm": d.b_mm, "h_mm": d.h_mm,
            "W_mm": d.W_mm, "body_length_mm": d.body_length_mm,
            "chamber_offset_mm": d.chamber_offset_mm,
            "body_material": d.body_material.as_dict(),
            "membrane_material": d.membrane_material.as_dict(),
        }


def material_from_input(value: str | OgdenMaterial | dict, field_name: str) -> OgdenMaterial:
    """A material given by preset id, as an OgdenMaterial, or as a dict
    ``{"id", "mu_kpa", "alpha"}``; errors name ``field_name``."""
    from solver.materials import make_material

    if isinstance(value, OgdenMaterial):
        return value
    if isinstance(value, str):
        from solver.design_space import named_material

        try:
            found = named_material(value)
        except InputError as exc:       # a scale the material's limits refuse (x1e308)
            raise InputError(field_name, f"{value!r}: {exc.detail}", exc.allowed) from None
        if found is None:
            import difflib

            # a typo's nearest preset (ecoflex_0030, Ecoflex_00_30, pdms_1-10)
            stem = value.split("*")[0].strip().lower().replace("-", "_")
            near = difflib.get_close_matches(stem, sorted(MATERIALS), n=1, cutoff=0.6)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise InputError(field_name, f"unknown material {value!r}{hint}",
                             ", ".join(sorted(MATERIALS)) + ", or <preset>*<scale> (every "
                             "mu_kpa of the preset times scale > 0)")
        return found
    if isinstance(value, dict):
        try:
            return make_material(str(value.get("id", "custom")), value["mu_kpa"], value["alpha"])
        except KeyError as exc:
            raise InputError(field_name, f"custom material lacks {exc.args[0]!r}",
                             "{id, mu_kpa: [...], alpha: [...]}") from None
        except InputError as exc:
            raise InputError(f"{field_name}.{exc.field}", exc.detail, exc.allowed) from None
    raise InputError(field_name, f"cannot read a material from {type(value).__name__}",
                     "a preset id or {id, mu_kpa, alpha}")


def design_from_dict(data: dict) -> Design:
    """Build and validate a Design from plain data (the inverse of ``as_dict``)."""
    known = set(LIMITS_MM) | {"body_material", "membrane_material"}
    unknown = set(data) - known
    if unknown:
        raise InputError(sorted(unknown)[0], "unknown design field", ", ".join(sorted(known)))
    kwargs: dict[str, object] = {}
    for name in LIMITS_MM:
        if data.get(name) is not None:
            try:
                value = data[name]    # a WrittenNumber (1e-400) refused as written
                kwargs[name] = value if isinstance(value, WrittenNumber) else float(value)
            except (TypeError, ValueError):
                raise InputError(name, f"not a number: {data[name]!r}") from None
    for name in ("body_material", "membrane_material"):
        if name in data:
            kwargs[name] = material_from_input(data[name], name)
    return Design(**kwargs).validated()  # type: ignore[arg-type]
