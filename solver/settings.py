"""Solver settings: discretisation, load control, tolerances and stop criteria."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Any

from solver.errors import InputError

CONTROLS = ("volume", "pressure")
ELEMENTS = ("hex2", "hex1")
TIPS = ("free", "spring", "blocked")
# the keys of solver.mesh.NAMED_DIVISIONS, least accurate first
MESH_DIVISIONS = ("former", "balanced", "fine_x")
# What records stored before the balanced mesh became the default call the former level 0
# (solver/store/schema.py reads it as "former"; users are told the new name).
LEGACY_MESH_DIVISIONS = {"default": "former"}

DEFAULT_MESH_LEVEL = 0  # within 2 % of the mesh-converged curve (docs/verification.md)
MAX_MESH_LEVEL = 2   # level 2: every division x 3, ~500k dofs at the standard design (a
                     # study level: many GB of memory)


# A syringe pump's flow rate, ul/s: MIN <= flow_ul_s <= MAX, one table for the solver's
# reported times, the service's pump view, the design search's time targets and measured
# data (surrogate.volume_control re-exports it). A slower pump is no pump (1e-320 ul/s made
# every time volume / flow infinite); 1000 ul/s fills the largest chamber of the box in
# well under a second, past what a quasi-static answer describes. (Until 2026-12-07 the
# solver's own upper limit was 1e6.)
MIN_FLOW_UL_S = 1e-6
MAX_FLOW_UL_S = 1000.0


# The numeric settings' ranges, lo <= value <= hi: one table for the check
# (SolverSettings.validated) and every refusal that names a setting's range (a grid
# file's ``mesh_level = 1.5`` as much as ``mesh_level = 9``).
SETTING_RANGES: dict[str, tuple[float, float]] = {
    "mesh_level": (0, MAX_MESH_LEVEL), "max_angle_deg": (0.1, 360.0),
    "max_pressure_pa": (1.0, 1e7), "max_volume_ul": (1e-3, 1e4),
    "flow_ul_s": (MIN_FLOW_UL_S, MAX_FLOW_UL_S), "bulk_ratio": (10.0, 1e6),
    "newton_tol": (1e-14, 1e-2), "max_newton_iter": (3, 200), "max_steps": (1, 10000),
    "spring_k_n_per_m": (0.0, 1e6),
}


def range_words(name: str, kind: str = "") -> str:
    """A numeric setting's allowed range in words (``SETTING_RANGES``), after ``kind``
    when given: ``"an integer 0 <= mesh_level <= 2"``; ``kind`` alone for a setting
    without a range."""
    if name not in SETTING_RANGES:
        return kind
    lo, hi = SETTING_RANGES[name]
    return f"{kind} {lo} <= {name} <= {hi}".lstrip()


@dataclass(frozen=True)
class SolverSettings:
    """How a design is solved.

    mesh_level        0 (coarsest) .. MAX_MESH_LEVEL; level n has n + 1 times the divisions
                      of level 0 in every direction (solver/mesh.py)
    mesh_divisions    the level-0 resolution: "balanced" (the default and the shipped
                      database's: walls graded to the chamber, two chamber layers; within
                      the issue-12 mesh targets), "former" (the default before it: 2.3-2.9
                      % low in angle) or "fine_x" (twice the former's divisions along x,
                      ~2x the dofs; docs/verification.md)
    element           "hex2" (27-node triquadratic, default) or "hex1" (8-node trilinear)
    control           "volume" (injected volume, pressure is an unknown) or "pressure"
    max_angle_deg     stop once the bending angle's magnitude reaches this
    max_pressure_pa   stop once the cavity pressure reaches this
    max_volume_ul     stop once the injected volume (whole actuator) reaches this
                      (the curve's last point lands on the stop: at or past it by at most
                      0.1 % of it and 0.01 deg; volume control, solver/landing.py; under
                      pressure control the pressure stop only, the others one step past;
                      a curve ending off a stop other than these defaults says where in
                      its reason)
    flow_ul_s         injection rate used to report time = volume / flow (the paper: 2.5)
    bulk_ratio        bulk modulus over initial shear modulus, K / mu0, per material
    newton_tol        relative residual ||R|| / ||p dV/du|| (a stall at the rounding floor
                      within 100 x newton_tol also counts as converged)
    max_newton_iter   iterations before a step is cut back
    max_steps         converged steps before the curve is ended
    tip               "free", "spring" (linear spring on the tip, k) or "blocked"
    spring_k_n_per_m  spring stiffness for tip = "spring" (whole actuator), N/m
    """

    mesh_level: int = DEFAULT_MESH_LEVEL
    mesh_divisions: str = "balanced"
    element: str = "hex2"
    control: str = "volume"
    max_angle_deg: float = 90.0
    max_pressure_pa: float = 20000.0
    max_volume_ul: float = 500.0
    flow_ul_s: float = 2.5
    bulk_ratio: float = 1000.0
    newton_tol: float = 1e-8
    max_newton_iter: int = 25
    max_steps: int = 400
    tip: str = "free"
    spring_k_n_per_m: float = 0.0

    def validated(self) -> SolverSettings:
        for name, (lo, hi) in SETTING_RANGES.items():
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or value != value or not lo <= value <= hi:
                raise InputError(name, f"got {value!r}", range_words(name))
        if self.mesh_divisions in LEGACY_MESH_DIVISIONS:
            raise InputError("mesh_divisions", f"{self.mesh_divisions!r} is the former name of "
                             f"{LEGACY_MESH_DIVISIONS[self.mesh_divisions]!r}; the default "
                             "mesh is 'balanced' (omit the setting for it)",
                             " | ".join(MESH_DIVISIONS))
        for name, allowed in (("element", ELEMENTS), ("control", CONTROLS), ("tip", TIPS),
                              ("mesh_divisions", MESH_DIVISIONS)):
            if getattr(self, name) not in allowed:
                raise InputError(name, f"got {getattr(self, name)!r}", " | ".join(allowed))
        if self.tip == "spring" and self.spring_k_n_per_m <= 0:
            raise InputError("spring_k_n_per_m", "a spring tip needs a positive stiffness",
                             "spring_k_n_per_m > 0")
        if self.tip != "spring" and self.spring_k_n_per_m != 0:
            # refused, not ignored: the stiffness would key a second record of one solve
            raise InputError("spring_k_n_per_m", f"a {self.tip} tip has no spring (got "
                             f"{self.spring_k_n_per_m!r})",
                             "spring_k_n_per_m = 0 unless tip = spring")
        return self

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


def settings_from_dict(data: dict) -> SolverSettings:
    """Build and validate settings from plain data; unknown keys are refused."""
    names = {f.name: f.type for f in fields(SolverSettings)}
    unknown = set(data) - set(names)
    if unknown:
        raise InputError(sorted(unknown)[0], "unknown solver setting", ", ".join(sorted(names)))
    kwargs: dict[str, Any] = {}
    defaults = SolverSettings()
    for key, value in data.items():
        kind = type(getattr(defaults, key))
        if kind in (int, float) and isinstance(value, bool):
            raise InputError(key, f"got {value!r}",
                             range_words(key, "an integer" if kind is int else "a number"))
        if kind is int and isinstance(value, float) and not value.is_integer():
            raise InputError(key, f"got {value!r}, which is not a whole number",
                             range_words(key, "an integer"))
        try:
            kwargs[key] = kind(value) if kind is not str else str(value)
        except (TypeError, ValueError):
            raise InputError(key, f"cannot read {value!r} as {kind.__name__}") from None
    return SolverSettings(**kwargs).validated()
