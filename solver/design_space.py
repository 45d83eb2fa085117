"""The design space labs vary: the box the emulator covers, defined once.

Geometry at W = 3 mm (the paper's width), lengths in mm:

    L 4-18, t 0.5-1.2, T 0.6-2.0, b 1.0-2.4, h 0.10-0.30

body length and chamber position by the solver's rules (``Design``), the paper's four
material pairs (body, membrane), each layer's Ogden mu optionally scaled by s (an inline
material with mu_kpa = s x the preset's and the preset's alpha). What the emulator enforces
(``locate(design, reduced=True)``, every query) is the ratio s_body / s_membrane in [1/4, 4]
(``REDUCED_RATIO_RANGE``), any common factor scaling only the pressure axis; each layer's
own s in [0.5, 2] (``STIFFNESS_SCALE_RANGE``) is what the design search ranges over.

Two invariances of the quasi-static hyperelastic problem are exact and used:

* scaling every length by k leaves angle(p) unchanged (the equations have no length
  scale), so a design at any W whose lengths are k x a box design's is in the box;
* scaling both layers' mu by s scales the pressure axis by s (stress is linear in mu at
  a fixed deformation), so only the ratio s_body / s_membrane changes the curve's shape:
  the database holds membranes at s = 1 and bodies at r = s_body / s_membrane in
  [1/4, 4] (the reduced box, ``REDUCED_RATIO_RANGE``).

Sampling: a scrambled Sobol sequence in the reduced box, lengths and the ratio in log
coordinates (relative changes matter, and the ratio's range is symmetric in log).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from functools import cache, lru_cache

import numpy as np

from solver.design import PAPER_WIDTH_MM, Design
from solver.errors import InputError
from solver.materials import MATERIALS, MIN_MU0_KPA, OgdenMaterial, make_material
from solver.number_text import ascii_float
from solver.ogden_paths import PATHS, STABLE_STRETCH_MAX, path_stress_kpa

BOX_WIDTH_MM = PAPER_WIDTH_MM        # the box is at the standard design's width
BOX_MM: dict[str, tuple[float, float]] = {
    "L_mm": (4.0, 18.0),
    "t_mm": (0.5, 1.2),
    "T_mm": (0.6, 2.0),
    "b_mm": (1.0, 2.4),
    "h_mm": (0.10, 0.30),
}
GEOMETRY = tuple(BOX_MM)
PAIRS: tuple[tuple[str, str], ...] = (
    ("pdms_1_10", "ecoflex_00_30"),
    ("pdms_1_15", "ecoflex_00_30"),
    ("ecoflex_00_30", "pdms_1_15"),
    ("ecoflex_00_30", "ecoflex_00_30"),
)
# Pairs whose bodies differ only in stiffness share one emulator: PDMS 1:10 and 1:15 have
# the same Ogden exponent to 1 % (3.268, 3.299; Table 1), so on the same membrane they are
# one material family whose coordinate is the stiffness contrast mu0_body / mu0_membrane.
GROUPS: dict[tuple[str, str], str] = {
    ("pdms_1_10", "ecoflex_00_30"): "pdms/ecoflex_00_30",
    ("pdms_1_15", "ecoflex_00_30"): "pdms/ecoflex_00_30",
    ("ecoflex_00_30", "pdms_1_15"): "ecoflex_00_30/pdms_1_15",
    ("ecoflex_00_30", "ecoflex_00_30"): "ecoflex_00_30/ecoflex_00_30",
}
STIFFNESS_SCALE_RANGE = (0.5, 2.0)
# A layer's stiffness scale S (mu = S x the preset's) that a single design or a search
# bound may state (the CLI's options, POST /v1/inverse's bounds); the box above lies within.
STIFFNESS_SCALE_LIMITS = (0.01, 100.0)
REDUCED_RATIO_RANGE = (STIFFNESS_SCALE_RANGE[0] / STIFFNESS_SCALE_RANGE[1],
                       STIFFNESS_SCALE_RANGE[1] / STIFFNESS_SCALE_RANGE[0])
# A material is "preset p scaled by s" when its alpha equal p's and its stress is s x p's
# within this relative tolerance at every stretch of RECOGNITION_STRETCHES (uniaxial,
# nominal), s the ratio of the term carrying the initial shear modulus: JSON round trips
# and 4-digit inputs stay inside, and so does a term that carries no stress there written
# to 3 digits
# (Ecoflex's mu = 7.879e-9 kPa at alpha 13.02 as 1.2e-8 for x1.5: 1.5 % off, refused until
# 2026-12-06 when each mu was held to 1e-3 of its own).
SCALE_TOLERANCE = 1e-3
# Up to 4: the stretches of the FE's range (a membrane ballooned to 90 deg of bending)
RECOGNITION_STRETCHES = np.linspace(1.05, STABLE_STRETCH_MAX, 60)
SAMPLED = (*GEOMETRY, "stiffness_ratio")   # coordinates of the reduced box, in order


def contrast(pair: tuple[str, str], stiffness_ratio: float) -> float:
    """Initial-shear-modulus contrast mu0_body / mu0_membrane of a reduced design."""
    return stiffness_ratio * MATERIALS[pair[0]].mu0_kpa / MATERIALS[pair[1]].mu0_kpa


@cache
def contrast_range(group: str) -> tuple[float, float]:
    """The contrast range the group's pairs cover in the reduced box (a constant of the
    box: computed once per group)."""
    pairs = [p for p, g in GROUPS.items() if g == group]
    lo, hi = REDUCED_RATIO_RANGE
    return (min(contrast(p, lo) for p in pairs), max(contrast(p, hi) for p in pairs))


def scaled_material(preset_id: str, scale: float) -> OgdenMaterial:
    """``preset_id``'s Ogden material with every mu multiplied by ``scale``; its id says
    so (``pdms_1_10*1.25``), so that its records never pass for the preset's."""
    base = MATERIALS[preset_id]
    if scale == 1.0:
        return base
    return make_material(f"{preset_id}*{scale:.6g}", [scale * m for m in base.mu_kpa],
                         list(base.alpha))


def named_material(material_id: str) -> OgdenMaterial | None:
    """The material an id names: a preset (``pdms_1_10``), or a preset with every mu
    scaled (``pdms_1_10*1.25``, as ``scaled_material`` names it); None for any other
    name."""
    preset_id, star, scale_text = material_id.partition("*")
    if not star:
        return MATERIALS.get(material_id)
    try:     # the one rule of numbers as text: float read '*1_0' as 10, '*１' as 1
        scale = ascii_float(scale_text)
    except ValueError:
        return None
    if preset_id not in MATERIALS:
        return None
    if not (math.isfinite(scale) and scale > 0):     # a preset's, with a scale no silicone has
        lo, hi = STIFFNESS_SCALE_LIMITS
        raise InputError("material", f"stiffness scale {scale_text.strip()} is not a "
                         "finite number > 0", f"<preset>*<scale>, {lo:g} <= scale <= {hi:g}")
    mu0_kpa = MATERIALS[preset_id].mu0_kpa
    if scale * mu0_kpa < MIN_MU0_KPA:   # refused by the scale, not by make_material's mu0
        lo, hi = STIFFNESS_SCALE_LIMITS
        raise InputError("material", f"stiffness scale {scale_text.strip()} makes mu0 "
                         f"{scale * mu0_kpa:.4g} kPa, softer than any material the FE is "
                         f"meant for", f"scale >= {MIN_MU0_KPA / mu0_kpa:.3g} for {preset_id} "
                         f"(mu0 >= {MIN_MU0_KPA:g} kPa); the emulator's box: {lo:g} <= s <= "
                         f"{hi:g}")
    return scaled_material(preset_id, scale)


REUSED_ID_ALLOWED = (f"a new id (presets: {', '.join(sorted(MATERIALS))}), the preset by "
                     "its id as a string, or <preset>*<scale> with every mu_kpa of the "
                     "preset times the scale")


def reused_id(material: OgdenMaterial) -> str | None:
    """What a custom material's id already names when its parameters are other ones:
    "preset id" or "scaled preset id" (one id, one set of parameters: a record stored
    under ``pdms_1_10*2`` is PDMS 1:10 with every mu doubled, wherever it is read); None
    when the id names no preset or names these parameters (a scaled preset's to the 6
    significant digits its id gives the scale with, ``f"{scale:.6g}"``)."""
    try:
        named = named_material(material.id)
    except InputError:          # a preset's id with a scale no material has (x0, xinf)
        return "scaled preset id"
    if named is None:
        return None
    rtol = 1e-5 if "*" in material.id else 0.0
    if (material.alpha == named.alpha and len(material.mu_kpa) == len(named.mu_kpa)
            and bool(np.allclose(material.mu_kpa, named.mu_kpa, rtol=rtol, atol=0.0))):
        return None
    return "preset id" if material.id in MATERIALS else "scaled preset id"


@lru_cache(maxsize=1024)
def recognise(material: OgdenMaterial) -> tuple[str, float] | None:
    """(preset id, s) when ``material`` is a preset with mu scaled by s (alpha equal,
    mu ratios equal within SCALE_TOLERANCE); None otherwise. The Ogden terms are a sum:
    they match in any order (an Ecoflex written with its alpha 13.02 term first). Remembered
    per material (a frozen value): a query asks it twice for the same two layers."""
    terms = sorted(zip(material.alpha, material.mu_kpa))
    for preset_id, base in MATERIALS.items():
        if len(base.alpha) != len(material.alpha):
            continue
        base_terms = sorted(zip(base.alpha, base.mu_kpa))
        if any(abs(a - b) > 1e-9 * max(1.0, abs(b))
               for (a, _), (b, _) in zip(terms, base_terms)):
            continue
        # s from the term that carries the initial shear modulus (exact for a preset
        # scaled as scaled_material writes it: 100 stays 100, a limit of the box)
        dominant = max(range(len(base_terms)), key=lambda i: abs(
            base_terms[i][0] * base_terms[i][1]))
        s = terms[dominant][1] / base_terms[dominant][1]
        ratio = uniaxial_stress_kpa(material) / uniaxial_stress_kpa(base)
        if s > 0 and bool(np.all(np.abs(ratio / s - 1.0) <= SCALE_TOLERANCE)):
            return preset_id, float(s)
    return None


def uniaxial_stress_kpa(material: OgdenMaterial,
                        stretch: np.ndarray = RECOGNITION_STRETCHES) -> np.ndarray:
    """Nominal stress (kPa) of the incompressible Ogden material in uniaxial tension at
    each ``stretch``: sum_p mu_p (l^(alpha_p - 1) - l^(-alpha_p / 2 - 1)), the derivative
    of solver.materials' W_iso along the uniaxial path (solver.ogden_paths)."""
    return path_stress_kpa(material.mu_kpa, material.alpha, stretch, PATHS["uniaxial"])


@dataclass(frozen=True)
class BoxPoint:
    """A design expressed in the box's terms.

    pair              (body preset, membrane preset)
    geometry_mm       L, t, T, b, h scaled to W = 3 mm
    stiffness_ratio   s_body / s_membrane
    pressure_scale    s_membrane: the design's pressures are this times the reduced
                      design's (membrane at its preset)
    length_scale      W / 3 mm
    """

    pair: tuple[str, str]
    geometry_mm: dict[str, float]
    stiffness_ratio: float
    pressure_scale: float
    length_scale: float

    @property
    def group(self) -> str:
        """The emulator that answers for this design (``GROUPS``)."""
        return GROUPS[self.pair]

    def reduced_design(self) -> Design:
        """The database design with the same angle(p / pressure_scale)."""
        body, membrane = self.pair
        return Design(body_material=scaled_material(body, self.stiffness_ratio),
                      membrane_material=MATERIALS[membrane], W_mm=BOX_WIDTH_MM,
                      **self.geometry_mm).validated()

    def coordinates(self) -> np.ndarray:
        """Unit-cube coordinates (log scale) of the reduced design in its group: the five
        lengths on the box's ranges, then the stiffness contrast on the group's range."""
        u = unit_coordinates(self.geometry_mm, REDUCED_RATIO_RANGE[0])
        u[-1] = _log_unit(contrast(self.pair, self.stiffness_ratio),
                          *contrast_range(self.group))
        return u


def _log_unit(value: float, lo: float, hi: float) -> float:
    return (math.log(value) - math.log(lo)) / (math.log(hi) - math.log(lo))


def unit_coordinates(geometry_mm: dict[str, float], stiffness_ratio: float) -> np.ndarray:
    """Unit-cube coordinates (0..1 inside the box) on a log scale."""
    u = [_log_unit(geometry_mm[n], *BOX_MM[n]) for n in GEOMETRY]
    u.append(_log_unit(stiffness_ratio, *REDUCED_RATIO_RANGE))
    return np.array(u)


def from_unit(u: np.ndarray) -> tuple[dict[str, float], float]:
    """Inverse of ``unit_coordinates``: (geometry_mm, stiffness_ratio)."""
    def val(x: float, lo: float, hi: float) -> float:
        return float(round(math.exp(math.log(lo) + x * (math.log(hi) - math.log(lo))), 6))

    geometry = {n: val(float(u[i]), *BOX_MM[n]) for i, n in enumerate(GEOMETRY)}
    return geometry, val(float(u[-1]), *REDUCED_RATIO_RANGE)


class OutOfBoxError(InputError):
    """A design outside the box; ``nearest`` is the closest design inside it. ``others``
    are the further fields outside the box (InputErrors, each with its own range): one
    refusal names every field to change, not one per request."""

    def __init__(self, field: str, detail: str, allowed: str, nearest: Design | None,
                 others: tuple[InputError, ...] = (), nearest_note: str = ""):
        self.own_detail, self.nearest_note = detail, nearest_note
        self.others = tuple(others)
        offer = "or solve this design with the FE (POST /v1/solve, `balloon solve`)"
        # each field's range beside it, then the nearest design and the offer: a range
        # at the end of the sentence read as the last clause's (an audit, 2026-12-06)
        text = (detail + (f" (allowed: {allowed})" if allowed else "")
                + "".join(f"; also {o.field}: {o.detail} (allowed: {o.allowed})"
                          for o in self.others))
        if nearest is not None:
            names = GEOMETRY + (("W_mm",) if nearest.W_mm != BOX_WIDTH_MM else ())
            lengths = ", ".join(f"{n}={getattr(nearest, n):g}" for n in names)
            text = (f"{text}; the nearest design inside the box{nearest_note}: {lengths} mm, "
                    f"{nearest.body_material.id}/{nearest.membrane_material.id}; {offer}")
        else:
            text = f"{text}{nearest_note}; {offer}"
        super().__init__(field, text, allowed, allowed_said=bool(allowed))
        self.nearest = nearest

    def renamed(self, names: dict[str, str]) -> OutOfBoxError:
        """The same refusal with its fields named as ``names`` maps them (a CLI's
        options: ``t_mm`` -> ``--t-mm``); names not in it stay."""
        others = tuple(InputError(names.get(o.field, o.field), o.detail, o.allowed)
                       for o in self.others)
        return OutOfBoxError(names.get(self.field, self.field), self.own_detail,
                             self.allowed or "", self.nearest, others, self.nearest_note)


def _preset_and_scale(material: OgdenMaterial, field: str) -> tuple[str, float]:
    found = recognise(material)
    if found is None:
        raise OutOfBoxError(field, f"material {material.id!r} is neither a preset nor a "
                            "preset with its mu scaled", "one of " + ", ".join(MATERIALS)
                            + " or one with every mu_kpa scaled by one factor s "
                            f"(alpha unchanged; its stress within {SCALE_TOLERANCE:g} of s "
                            "times the preset's at stretches up to 4)", None)
    return found


def pair_bending_alike(body: str, membrane: str, stiffness_ratio: float = 1.0
                       ) -> tuple[tuple[str, str] | None, str]:
    """The pair of the box that bends the same way as (``body``, ``membrane``) with the
    layers' scales in the ratio ``stiffness_ratio`` (s_body / s_membrane), and a note
    saying so for the refusal's nearest design.

    The direction follows the layers' stiffness contrast mu0_body / mu0_membrane: a
    stiffer body bends the actuator away from the membrane (positive angles), a stiffer
    membrane towards it (negative), equal layers either way by the geometry. Of the box's
    pairs on the same side of 1, the nearest contrast (log scale); (None, why) when no
    pair of the box is on that side."""
    def side(c: float) -> int:
        return 0 if abs(math.log(c)) < 1e-9 else (1 if c > 1 else -1)

    c = stiffness_ratio * MATERIALS[body].mu0_kpa / MATERIALS[membrane].mu0_kpa
    alike = [p for p in PAIRS if side(contrast(p, 1.0)) == side(c)]
    words = {1: "bends the same way (away from the membrane: a stiffer body)",
             -1: "bends the same way (towards the membrane: a stiffer membrane)",
             0: "has layers of equal stiffness, as this pair"}[side(c)]
    if not alike:
        return None, "; no pair in the box " + words.replace("bends", "bend", 1)
    best = min(alike, key=lambda p: abs(math.log(contrast(p, 1.0) / c)))
    return best, f" that {words}"


def locate(design: Design, reduced: bool = False) -> BoxPoint:
    """The design in the box's terms; OutOfBoxError (naming the field, the range and the
    nearest in-box design) when it is outside. ``reduced``: check only the stiffness
    ratio s_body / s_membrane against REDUCED_RATIO_RANGE (database designs: membrane at
    its preset, body at the ratio), not each layer's scale."""
    design = design.validated()
    body, s_body = _preset_and_scale(design.body_material, "body_material")
    membrane, s_membrane = _preset_and_scale(design.membrane_material, "membrane_material")
    k = design.W_mm / BOX_WIDTH_MM
    geometry = {n: getattr(design, n) / k for n in GEOMETRY}
    nearest_geometry = {n: min(max(v, BOX_MM[n][0]), BOX_MM[n][1])
                        for n, v in geometry.items()}
    lo_s, hi_s = STIFFNESS_SCALE_RANGE
    near_sb, near_sm = (min(max(s, lo_s), hi_s) for s in (s_body, s_membrane))

    def nearest(pair: tuple[str, str] = (body, membrane)) -> Design:
        # at the design's own width: the in-box design's scaled copy, default body
        return Design(body_material=scaled_material(pair[0], near_sb),
                      membrane_material=scaled_material(pair[1], near_sm),
                      W_mm=design.W_mm, **{n: round(k * v, 6) for n, v in
                                           nearest_geometry.items()}).validated()

    if (body, membrane) not in PAIRS:
        allowed = ", ".join(f"{b}/{m}" for b, m in PAIRS)
        same_way, note = pair_bending_alike(body, membrane, s_body / s_membrane)
        raise OutOfBoxError("body_material", f"pair {body}/{membrane} is not in the box",
                            allowed, None if same_way is None else nearest(same_way),
                            nearest_note=note)
    outside = []
    for n, v in geometry.items():
        lo, hi = BOX_MM[n]
        if not lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9):
            scaled = "" if k == 1 else f" (scaled to W = 3 mm: {v:.4g} mm)"
            outside.append(InputError(n, f"{n} = {getattr(design, n):g} mm{scaled} is "
                                      "outside the emulator's box",
                                      f"{lo:g} <= {n} <= {hi:g} mm at W = 3 mm (or the same "
                                      "ratios to W)"))
    if outside:
        first = outside[0]
        raise OutOfBoxError(first.field, first.detail, first.allowed or "", nearest(),
                            tuple(outside[1:]))
    for field, s in (("body_material", s_body), ("membrane_material", s_membrane)):
        lo_l, hi_l = STIFFNESS_SCALE_LIMITS
        if reduced and not lo_l <= s <= hi_l:
            # a common factor scales only the pressure axis, but a layer 1e-300 or 9999
            # times its preset is no silicone of this family (an audit, 2026-12-06)
            raise OutOfBoxError(field, f"stiffness scale {s:.4g} (mu_kpa = s x the preset's) "
                                "is past any silicone of this family",
                                f"{lo_l:g} <= s <= {hi_l:g} for each layer, "
                                f"{REDUCED_RATIO_RANGE[0]:g} <= s_body / s_membrane <= "
                                f"{REDUCED_RATIO_RANGE[1]:g}", nearest())
    if reduced:
        ratio = s_body / s_membrane
        lo_s, hi_s = REDUCED_RATIO_RANGE
        if not lo_s * (1 - SCALE_TOLERANCE) <= ratio <= hi_s * (1 + SCALE_TOLERANCE):
            # the layer whose own scale strays from the box's is the one to change
            lo_layer, hi_layer = STIFFNESS_SCALE_RANGE
            field = ("membrane_material" if lo_layer <= s_body <= hi_layer
                     and not lo_layer <= s_membrane <= hi_layer else "body_material")
            raise OutOfBoxError(field, f"the layers' stiffness ratio s_body / s_membrane = "
                                f"{ratio:.4g} (body x{s_body:.4g}, membrane x{s_membrane:.4g} of "
                                "their presets' mu_kpa) is outside the box; only the ratio "
                                "matters, scaling both scales the pressure axis",
                                f"{lo_s:g} <= s_body / s_membrane <= {hi_s:g}", nearest())
    else:
        for field, s in (("body_material", s_body), ("membrane_material", s_membrane)):
            lo_s, hi_s = STIFFNESS_SCALE_RANGE
            if not lo_s * (1 - SCALE_TOLERANCE) <= s <= hi_s * (1 + SCALE_TOLERANCE):
                raise OutOfBoxError(field, f"stiffness scale {s:.4g} is outside the box",
                                    f"{lo_s:g} <= s <= {hi_s:g} (mu_kpa = s x the "
                                    "preset's)", nearest())
    rule = replace(Design(W_mm=BOX_WIDTH_MM, **geometry), body_length_mm=None,
                   chamber_offset_mm=None).validated()
    for name in ("body_length_mm", "chamber_offset_mm"):
        expected = getattr(rule, name) * k
        if abs(getattr(design, name) - expected) > 1e-6 * max(1.0, expected):
            raise OutOfBoxError(name, f"{name} = {getattr(design, name):g} mm differs from "
                                "the solver's rule that the emulator was built with",
                                f"{name} = {expected:.6g} mm for this design (the default: "
                                "body max(12, L + 2) mm at W = 3, scaled with W; chamber "
                                "centred)",
                                nearest())
    return BoxPoint((body, membrane), geometry, s_body / s_membrane, s_membrane, k)


def sobol_points(n: int, seed: int = 0, skip: int = 0) -> np.ndarray:
    """``n`` scrambled Sobol points in the reduced box's unit cube (rows, SAMPLED order),
    after skipping the first ``skip`` (so that a later call continues the sequence)."""
    from scipy.stats import qmc

    if not 1 <= n <= 100_000:
        raise InputError("n", f"got {n}", "1 <= n <= 100000")
    engine = qmc.Sobol(d=len(SAMPLED), scramble=True, seed=seed)
    if skip:
        engine.fast_forward(skip)
    with warnings.catch_warnings():
        # scipy warns when n is not a power of 2 (the sequence's balance); a grid may
        # continue a sequence in any step, and the union stays a prefix of it
        warnings.simplefilter("ignore", UserWarning)
        return engine.random(n)


def on_faces(points: np.ndarray, skip: int = 0) -> np.ndarray:
    """The unit-cube ``points`` moved onto the box's faces: point i (counted from
    ``skip``, so that a continued sequence goes on where it stopped) has coordinate
    i mod d set to 0 for even i // d, else 1 -- the 2 d faces in turn, the other
    coordinates space-filling. A GP reads a design near a face from data on one side
    only: held-out curves within 0.05 (unit, log scale) of a face missed the per-curve
    target 4-5 x as often as those 0.1 or more inside (benchmarks/RESULTS.md, forty-third
    session); designs on the faces put data on the box's boundary."""
    out = np.array(points, dtype=float, copy=True)
    d = out.shape[1]
    for row, i in enumerate(range(skip, skip + len(out))):
        out[row, i % d] = float((i // d) % 2)
    return out


def sample_designs(n: int, pair: tuple[str, str], seed: int = 0, skip: int = 0,
                   faces: bool = False) -> list[Design]:
    """``n`` space-filling database designs of ``pair`` (membrane at its preset, body at
    the sampled stiffness ratio); ``faces``: moved onto the box's faces (``on_faces``)."""
    points = sobol_points(n, seed, skip)
    out = []
    for u in (on_faces(points, skip) if faces else points):
        geometry, ratio = from_unit(u)
        out.append(Design(body_material=scaled_material(pair[0], ratio),
                          membrane_material=MATERIALS[pair[1]], W_mm=BOX_WIDTH_MM,
                          **geometry).validated())
    return out
