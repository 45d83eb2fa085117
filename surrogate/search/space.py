"""The space a design search ranges over: each variable's bounds, the candidates drawn in
them, and a candidate as a ``Design``.

Variables (``VARIABLES``): the lengths L, t, T, b, h (mm, at the box's width
``BOX_WIDTH_MM``) within the user's bounds clipped to ``solver.design_space.BOX_MM``,
and each layer's stiffness scale (dimensionless, mu = scale x the preset's) within
``STIFFNESS_SCALE_RANGE`` (default 1: the presets as sold). Candidates are scrambled
Sobol points, log-uniform in every bound (lengths and scales are positive and act on
the curve by ratios); a model that covers only slices of the box (the exponential
model: fixed T, b, h per family) has them pinned to its slices. A candidate's place in
the bounds' unit cube (``unit_coordinates``, log scale) is what "near" means when the
ranking drops near-copies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver.design import Design
from solver.design_space import (
    BOX_MM,
    BOX_WIDTH_MM,
    GEOMETRY,
    PAIRS,
    STIFFNESS_SCALE_RANGE,
    scaled_material,
)
from solver.errors import InputError

#: Sobol candidates per material pair (a model with no batch screen takes a quarter)
CANDIDATES_PER_PAIR = 512
#: the searched variables: the lengths (mm), then each layer's stiffness scale
VARIABLES = (*GEOMETRY, "body_stiffness_scale", "membrane_stiffness_scale")


@dataclass(frozen=True)
class SearchBounds:
    """(low, high) per geometry field (mm) and per layer's stiffness scale; None = the
    box for geometry, (1, 1) for the scales. ``pairs``: allowed (body, membrane) ids."""

    L_mm: tuple[float, float] | None = None
    t_mm: tuple[float, float] | None = None
    T_mm: tuple[float, float] | None = None
    b_mm: tuple[float, float] | None = None
    h_mm: tuple[float, float] | None = None
    body_stiffness_scale: tuple[float, float] | None = None
    membrane_stiffness_scale: tuple[float, float] | None = None
    pairs: tuple[tuple[str, str], ...] | None = None

    def ranges(self) -> dict[str, tuple[float, float]]:
        """Validated ranges of every searched variable, clipped to the box."""
        out: dict[str, tuple[float, float]] = {}
        for name in GEOMETRY:
            out[name] = self._range(name, getattr(self, name), BOX_MM[name], "mm")
        for name in ("body_stiffness_scale", "membrane_stiffness_scale"):
            out[name] = self._range(name, getattr(self, name), STIFFNESS_SCALE_RANGE, "",
                                    default=(1.0, 1.0))
        return out

    @staticmethod
    def _range(name: str, value: tuple[float, float] | None, box: tuple[float, float],
               unit: str, default: tuple[float, float] | None = None
               ) -> tuple[float, float]:
        if value is None:
            return default or box
        lo, hi = (float(v) for v in value)
        if not (np.isfinite(lo) and np.isfinite(hi)) or not 0 < lo <= hi:
            # lengths and stiffness scales are positive: [-1, 5] is no bound to clip
            raise InputError(name, f"bounds {list(value)!r}",
                             "[low, high] with 0 < low <= high")
        if hi < box[0] or lo > box[1]:
            raise InputError(name, f"bounds {list(value)!r} lie outside the box",
                             f"within {box[0]:g}..{box[1]:g} {unit}".rstrip())
        return max(lo, box[0]), min(hi, box[1])

    def clipped(self, ranges: dict[str, tuple[float, float]]) -> list[str]:
        """What ``ranges`` (``ranges()``) searched where the bounds given reach past the
        box: "L_mm 4-18 (of 2-30 given)" -- said with the answer, so that "no design meets
        the target" is not read as covering what was never searched."""
        out = []
        for name, (lo, hi) in ranges.items():
            given = getattr(self, name)
            if given is not None and (float(given[0]), float(given[1])) != (lo, hi):
                out.append(f"{name} {lo:g}-{hi:g} (of {float(given[0]):g}-"
                           f"{float(given[1]):g} given)")
        return out

    def allowed_pairs(self) -> tuple[tuple[str, str], ...]:
        """The (body, membrane) preset pairs searched: every pair of the box, or those
        given (each once, in the order given); InputError naming ``material_pairs``
        for a pair outside the box."""
        if self.pairs is None:
            return PAIRS
        for pair in self.pairs:
            if tuple(pair) not in PAIRS:
                scaled = (" (a layer's stiffness scale is searched within its bounds: "
                          "body_stiffness_scale_bounds, membrane_stiffness_scale_bounds)"
                          if "*" in pair[0] + pair[1] else "")
                raise InputError("material_pairs", f"pair {pair[0]}/{pair[1]} is not in the "
                                 f"box{scaled}", ", ".join(f"{b}/{m}" for b, m in PAIRS))
        # each pair once, in the order given: a repeated pair would be searched again
        return tuple(dict.fromkeys(tuple(p) for p in self.pairs))  # type: ignore[misc]


def candidate_design(pair: tuple[str, str], values: dict[str, float]) -> Design:
    """The validated ``Design`` of ``values`` (lengths in mm, stiffness scales) for the
    preset pair ``pair``, at the box's width."""
    return Design(body_material=scaled_material(pair[0], values["body_stiffness_scale"]),
                  membrane_material=scaled_material(pair[1],
                                                    values["membrane_stiffness_scale"]),
                  W_mm=BOX_WIDTH_MM, **{n: values[n] for n in GEOMETRY}).validated()


def sobol_candidates(ranges: dict[str, tuple[float, float]], slices: list[dict] | None,
                     seed: int, count: int = CANDIDATES_PER_PAIR) -> list[dict[str, float]]:
    """``count`` scrambled Sobol points (``seed``), log-uniform in every range of
    ``ranges``, as {variable: value}; with ``slices`` (a model's covered (T, b, h) in mm)
    the first points again on each slice inside the ranges, T, b, h pinned to it and the
    scales to 1."""
    from scipy.stats import qmc

    u = qmc.Sobol(d=len(VARIABLES), scramble=True, seed=seed).random(count)
    out = []
    for row in u:
        values = {}
        for x, name in zip(row, VARIABLES):
            lo, hi = ranges[name]
            values[name] = float(lo * (hi / lo) ** x) if hi > lo else lo
        out.append(values)
    if slices is None:
        return out
    pinned = []
    for sl in slices:  # a model that covers slices: pin T, b, h (and the scales to 1)
        if not all(ranges[n][0] - 1e-9 <= sl[n] <= ranges[n][1] + 1e-9
                   for n in ("T_mm", "b_mm", "h_mm")):
            continue
        for v in out[: max(count // max(len(slices), 1), 16)]:
            pinned.append({**v, "T_mm": sl["T_mm"], "b_mm": sl["b_mm"], "h_mm": sl["h_mm"],
                           "body_stiffness_scale": 1.0, "membrane_stiffness_scale": 1.0})
    return pinned


def unit_coordinates(values: dict[str, float], ranges: dict[str, tuple[float, float]]
                     ) -> np.ndarray:
    """``values``' place in the unit cube of ``ranges``, on a log scale (0 for a pinned
    variable): the distance the ranking's near-copies are measured in."""
    out = []
    for name in VARIABLES:
        lo, hi = ranges[name]
        out.append(0.0 if hi <= lo else np.log(values[name] / lo) / np.log(hi / lo))
    return np.array(out)
