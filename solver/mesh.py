"""Parametric hexahedral mesh of the half actuator (symmetry plane y = 0).

A tensor-product grid whose lines pass through every interface (chamber ends,
chamber side, membrane top, chamber roof), with the elements inside the chamber
removed. Mesh level n multiplies every division of level 0 by n + 1, in every
direction and every segment, so that the levels are a nested family with element
sizes h0 / (n + 1): the sequence the convergence study's Richardson estimate needs
(docs/verification.md). Spacing is graded towards the chamber: the walls beyond the
chamber ends grow geometrically away from it, and the body above the chamber grows
upwards, so resolution sits where the membrane bulges and the body bends.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from skfem import MeshHex

from solver.design import Design
from solver.settings import SolverSettings


@dataclass(frozen=True)
class MeshDivisions:
    """Level-0 resolution: element sizes along x (mm) and division counts per segment."""

    x_chamber_mm: float = 1.0       # element size along the chamber, at W = 3 mm
    x_wall_mm: float = 1.5          # along the end walls (graded away from the chamber)
    y_chamber: int = 4              # across the half chamber width b/2
    y_side: int = 2                 # across the side wall, b/2 .. W/2 (graded)
    membrane: int = 2               # layers through the membrane thickness t
    chamber: int = 1                # layers through the chamber height h
    body: int = 2                   # layers through the body above the chamber T (graded)
    x_refine: int = 1               # every x count above times this (nested x families)
    x_chamber_grading: float = 1.0  # largest / smallest element along the chamber (dense
                                    # at both chamber ends, where the membrane is bonded)
    x_wall_grading: float = 1.6     # largest / smallest along each end wall (dense at the
                                    # chamber end; GRADING_RATIO)


# The former level 0 (x_refine = 1), the default until the database was rebuilt on the
# balanced mesh (issue 12). The convergence study (docs/verification.md) found its error
# along x and in the chamber layer: against the three-level extrapolation (observed order
# 2.3-2.8) the angle at 1000-2000 Pa is -2.3 to -2.9 % and the pressure at 10-60 deg +0.4
# to +0.9 %. Selectable as mesh_divisions = "former" (records stored before the switch
# say "default", read as "former": solver/store/schema.py; their keys hold,
# solver/store/keys.py).
FORMER_DIVISIONS = MeshDivisions()
FINE_X_DIVISIONS = MeshDivisions(x_refine=2)
# The default: the former level 0's divisions spent where its error sits
# (docs/verification.md, "A balanced level 0"): the end walls graded 3:1 towards the
# chamber's bonded ends (was 1.6:1), two layers through the chamber height instead of one,
# and 1.1 mm along the chamber instead of 1.0 (uniform: chambers graded towards their
# ends, or walls graded 5:1, reached the targets too but ended database curves early with
# Newton failures at membrane stretches of 8-9). 1.03 x the dofs of the former level 0 on
# the standard design and its full curve in 1.02 x the time; against the three-level
# extrapolation it reads the angle at 1000-2000 Pa within -0.7 to -1.3 % and the pressure
# at 10-60 deg within +0.1 to +0.5 %: both issue-12 targets.
BALANCED_DIVISIONS = MeshDivisions(x_chamber_mm=1.1, chamber=2, x_wall_grading=3.0)
DEFAULT_DIVISIONS = BALANCED_DIVISIONS
# The level-0 resolutions a user selects by name (SolverSettings.mesh_divisions), least
# accurate first (the order ranks a database's records, surrogate/dataset.py).
NAMED_DIVISIONS = {"former": FORMER_DIVISIONS, "balanced": BALANCED_DIVISIONS,
                   "fine_x": FINE_X_DIVISIONS}
COARSE_DIVISIONS = MeshDivisions(y_chamber=2, y_side=1, membrane=1)
GRADING_RATIO = 1.6     # largest / smallest element in a graded segment
REFERENCE_WIDTH_MM = 3.0   # the x element sizes are given at this width (the paper's W)
# The family of the convergence study along x and through the chamber and body layers
# (docs/verification.md): member r has r times the x, chamber and body divisions of the
# former level 0 and its divisions across the width and through the membrane (where
# doubling moves p at 30 deg by 0.2 Pa).
XZ_BASE = FORMER_DIVISIONS


def xz_family(r: int) -> MeshDivisions:
    """Member r (1, 2, 3, ...) of the x-and-layers family: element size h = 1 / r there."""
    return replace(XZ_BASE, x_refine=r, chamber=r * XZ_BASE.chamber, body=r * XZ_BASE.body)


@dataclass(frozen=True)
class ActuatorMesh:
    """The mesh and the sets the solver needs (lengths in mm)."""

    mesh: MeshHex
    membrane: np.ndarray        # bool per element: True in membrane B, else body A
    cavity_facets: np.ndarray   # facet indices of the chamber's walls (outward normal into it)
    end_face_x_mm: float        # x of the free end


def refinement(level: int) -> int:
    """Divisions of level ``level`` per division of level 0."""
    return level + 1


def _segment(a: float, b: float, n: int, dense_at: str | None = None,
             ratio: float = 0.0) -> np.ndarray:
    """n elements on [a, b]; geometric grading with the small ones at 'a' or 'b', largest /
    smallest = ``ratio`` (GRADING_RATIO when 0)."""
    if n == 1 or dense_at is None:
        return np.linspace(a, b, n + 1)
    q = (ratio or GRADING_RATIO) ** (1.0 / (n - 1))
    sizes = q ** np.arange(n)
    if dense_at == "b":
        sizes = sizes[::-1]
    return _points(a, b, sizes)


def _symmetric_segment(a: float, b: float, n: int, ratio: float) -> np.ndarray:
    """n elements on [a, b], graded geometrically from both ends to the middle with
    largest / smallest = ``ratio`` (1: uniform)."""
    if ratio == 1.0 or n < 3:
        return np.linspace(a, b, n + 1)
    half = (n + 1) // 2
    q = ratio ** (1.0 / max(half - 1, 1))
    sizes = q ** np.arange(half)
    sizes = np.concatenate((sizes, sizes[::-1][n % 2:]))            # n sizes, symmetric
    return _points(a, b, sizes)


def _points(a: float, b: float, sizes: np.ndarray) -> np.ndarray:
    """Points from a to b with spacings proportional to ``sizes``; the ends exactly a and
    b, so that the segments' shared points join into one (a rounded end left a sliver
    element of zero width when the segments were joined)."""
    points = a + (b - a) * np.concatenate(([0.0], np.cumsum(sizes) / sizes.sum()))
    points[0], points[-1] = a, b
    return points


def _join(*segments: np.ndarray) -> np.ndarray:
    return np.unique(np.concatenate(segments))



def grid_lines(design: Design, level: int, divisions: MeshDivisions = DEFAULT_DIVISIONS
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The half mesh's grid lines x, y, z (mm) of a validated design at ``level``
    (``build_mesh``'s tensor grid, before the chamber's elements are removed)."""
    d = design
    assert d.chamber_offset_mm is not None and d.body_length_mm is not None  # validated
    x0 = float(d.chamber_offset_mm)
    x1 = x0 + d.L_mm
    xb = float(d.body_length_mm)
    r = refinement(level)
    rx = r * divisions.x_refine

    # Element sizes along x scale with the width, so that a design scaled by k in every
    # length gets the mesh scaled by k: the FE keeps the problem's exact invariance
    # (angle(p) unchanged), and the emulator relies on it (solver/design_space.py).
    k = d.W_mm / REFERENCE_WIDTH_MM
    n_ch = rx * max(2, int(np.ceil(d.L_mm / (k * divisions.x_chamber_mm) - 1e-9)))
    n_left = rx * max(1, int(np.ceil(x0 / (k * divisions.x_wall_mm) - 1e-9)))
    n_right = rx * max(1, int(np.ceil((xb - x1) / (k * divisions.x_wall_mm) - 1e-9)))
    x = _join(_segment(0.0, x0, n_left, "b", divisions.x_wall_grading),
              _symmetric_segment(x0, x1, n_ch, divisions.x_chamber_grading),
              _segment(x1, xb, n_right, "a", divisions.x_wall_grading))

    yb, yw = 0.5 * d.b_mm, 0.5 * d.W_mm
    y = _join(np.linspace(0.0, yb, r * divisions.y_chamber + 1),
              _segment(yb, yw, r * divisions.y_side, "a"))

    z_m, z_c = d.t_mm, d.t_mm + d.h_mm
    z_top = z_c + d.T_mm
    z = _join(np.linspace(0.0, z_m, r * divisions.membrane + 1),
              np.linspace(z_m, z_c, r * divisions.chamber + 1),
              _segment(z_c, z_top, r * divisions.body, "a"))
    return x, y, z


def estimated_dofs(design: Design, settings: SolverSettings) -> int:
    """Degrees of freedom of the half model of ``design`` solved with ``settings`` (its
    mesh level, divisions and element), from the grid alone (no mesh built): three per
    node of the tensor grid, a triquadratic element ("hex2") adding the edge, face and
    centre nodes. An upper bound (the chamber's nodes and the clamp's fixed ones are
    counted; 11.7k at the standard design, whose solve has 10.0k): what a solve's memory
    grows with."""
    x, y, z = grid_lines(design.validated(), settings.mesh_level,
                         NAMED_DIVISIONS[settings.mesh_divisions])
    q = 2 if settings.element == "hex2" else 1
    return 3 * (q * (len(x) - 1) + 1) * (q * (len(y) - 1) + 1) * (q * (len(z) - 1) + 1)


def build_mesh(design: Design, level: int,
               divisions: MeshDivisions = DEFAULT_DIVISIONS,
               full_width: bool = False) -> ActuatorMesh:
    """Mesh the half actuator of a validated design at refinement ``level`` (>= 0):
    every division of ``divisions`` times level + 1. ``full_width``: the whole width
    instead, -W/2 <= y <= W/2 (the half mesh and its mirror image), for checking what
    the symmetry plane hides (benchmarks/full_width_check.py); the solver uses the half."""
    d = design.validated()
    x, y, z = grid_lines(d, level, divisions)
    if full_width:
        y = _join(-y, y)
    assert d.chamber_offset_mm is not None and d.body_length_mm is not None  # validated
    x0 = float(d.chamber_offset_mm)
    x1 = x0 + d.L_mm
    xb = float(d.body_length_mm)
    yb = 0.5 * d.b_mm
    z_m, z_c = d.t_mm, d.t_mm + d.h_mm

    mesh = MeshHex.init_tensor(x, y, z)
    centroids = mesh.p[:, mesh.t].mean(axis=1)
    in_cavity = ((centroids[0] > x0) & (centroids[0] < x1) & (np.abs(centroids[1]) < yb)
                 & (centroids[2] > z_m) & (centroids[2] < z_c))
    mesh = mesh.remove_elements(np.nonzero(in_cavity)[0])
    centroids = mesh.p[:, mesh.t].mean(axis=1)
    membrane = centroids[2] < z_m

    tol = 1e-9 * max(xb, 1.0)
    bf = mesh.boundary_facets()
    mid = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    on_cavity = ((mid[0] > x0 - tol) & (mid[0] < x1 + tol) & (np.abs(mid[1]) < yb + tol)
                 & ((mid[1] > tol) | full_width) & (mid[2] > z_m - tol) & (mid[2] < z_c + tol))
    return ActuatorMesh(mesh=mesh, membrane=membrane, cavity_facets=bf[on_cavity],
                        end_face_x_mm=xb)
