"""Cross-check of the FE solver against felupe on the standard actuator.

Same geometry and mesh (``solver.mesh.build_mesh``'s points and cells), same materials
(the paper's Ogden sets; felupe's Ogden form is sum 2 mu_f / alpha^2 (...), so
mu_f = mu alpha / 2), same bulk modulus (K = bulk_ratio x mu0 per material), same
boundary conditions (clamped x = 0, symmetry y = 0), follower pressure on the chamber
walls, pressure control with the same increments. Both codes' wall times are measured
in the same run.

Elements (``--element``):

- hex1: Hex1 with a constant pressure / mean dilatation per element (felupe's
  SolidBodyNearlyIncompressible).
- hex2, the production element: the 27-node triquadratic hexahedron with felupe's
  three-field (u, p, J) formulation (``NearlyIncompressible``: W_iso(F) + K/2 (J_bar-1)^2
  + p (J - J_bar), with p and J_bar discontinuous between elements). Eliminating p and
  J_bar element by element gives exactly our condensed energy K/2 g^T M^-1 g
  (solver/assembly.py) when both use the same pressure space. ``--pressure-space p1``
  (default) is ours, linear in the element (1, x, y, z; Q2/P1-disc), built as a felupe
  Region with a 4-function element on felupe's disconnected dual mesh; ``q1`` is
  felupe's own choice for this element, trilinear per element (8 functions), which is
  a different discretisation (it shows how much the pressure space matters).

    .venv/bin/python benchmarks/bench_felupe.py [--level 1] [--pmax 1500] [--dp 100]
    .venv/bin/python benchmarks/bench_felupe.py --element hex2 --level 0 [--pressure-space p1]

felupe is an optional benchmark extra (pyproject ``benchmark``); results are
recorded in benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from solver import Design, SolverSettings
from solver.discrete import ActuatorModel
from solver.mesh import build_mesh
from solver.verification.drive import drive_pressure

# VTK hexahedron corner order as (x, y, z) bits of the box's corners.
VTK_CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
               (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]


def vtk_cells(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Reorder the corners of axis-aligned box cells (ncells, 8) into VTK order."""
    xyz = points[cells]                                            # (nc, 8, 3)
    centre = xyz.mean(axis=1, keepdims=True)
    bits = (xyz > centre).astype(int)                              # (nc, 8, 3)
    code = bits[..., 0] + 2 * bits[..., 1] + 4 * bits[..., 2]
    order = np.array([x + 2 * y + 4 * z for x, y, z in VTK_CORNERS])
    pos = np.argsort(code, axis=1)                                 # corner with code c
    return np.take_along_axis(cells, pos[:, order], axis=1)


def _node_map(felupe_points: np.ndarray, doflocs: np.ndarray) -> np.ndarray:
    """Index of each felupe point among our nodes (doflocs (3, n)), matched by position."""
    ours = np.round(doflocs.T, 9)
    theirs = np.round(felupe_points, 9)
    if ours.shape != theirs.shape:
        raise RuntimeError(f"felupe has {len(theirs)} points, we have {len(ours)} nodes")
    a = np.lexsort(ours.T[::-1])
    b = np.lexsort(theirs.T[::-1])
    if not np.array_equal(ours[a], theirs[b]):
        raise RuntimeError("felupe's points are not our nodes")
    index = np.empty(len(theirs), dtype=int)
    index[b] = a
    return index


def _on_chamber_walls(design, points: np.ndarray) -> np.ndarray:
    """Points on the surface of the (half) chamber box: every node of a wall face."""
    x0 = design.chamber_offset_mm
    lo = np.array([x0, 0.0, design.t_mm])
    hi = np.array([x0 + design.L_mm, 0.5 * design.b_mm, design.t_mm + design.h_mm])
    tol = 1e-9 * max(design.body_length_mm, 1.0)
    inside = np.all((points > lo - tol) & (points < hi + tol), axis=1)
    on_face = np.any(np.abs(points - lo) < tol, axis=1) | np.any(np.abs(points - hi) < tol,
                                                                  axis=1)
    return inside & on_face


class P1Disc:
    """The pressure space of our hex2 (solver/assembly.py): 1, r, s, t in the element
    (on box elements the same span as 1, x, y, z), as a felupe element."""

    def function(self, rst):
        return np.array([1.0, *rst])

    def gradient(self, rst):
        return np.vstack([np.zeros(3), np.eye(3)])


class CellwiseMaterial:
    """Two (or more) felupe hyperelastic materials on disjoint cell sets, as one
    material of the isochoric part (felupe's dual fields cannot be split into bodies)."""

    def __init__(self, materials, cell_masks) -> None:
        self.materials = materials
        self.masks = cell_masks
        self.x = materials[0].x

    def _split(self, x, mask):
        F, statevars = x
        sv = statevars[..., mask] if getattr(statevars, "ndim", 0) >= 2 else statevars
        return [F[..., mask], sv]

    def gradient(self, x):
        P = np.zeros_like(x[0])
        for mat, mask in zip(self.materials, self.masks):
            P[..., mask] = mat.gradient(self._split(x, mask))[0]
        return [P, x[-1]]

    def hessian(self, x):
        F = x[0]
        A = np.zeros((3, 3, 3, 3) + F.shape[2:])
        for mat, mask in zip(self.materials, self.masks):
            A[..., mask] = mat.hessian(self._split(x, mask))[0]
        return [A]


def _ogden(block):
    import felupe.constitution.tensortrax as mat

    mu_f = list(block.mu_pa * block.alpha / 2.0)
    return (mat.Hyperelastic(mat.models.hyperelastic.ogden, mu=mu_f, alpha=list(block.alpha)),
            float(sum(mu_f)))


def _hex1_problem(fem, model, bulk_ratio):
    """Mesh, top-level field, solid bodies and the node map for Hex1 (mean dilatation)."""
    points = model.mesh.p.T.copy()
    cells = vtk_cells(points, model.mesh.t.T)
    membrane = np.zeros(len(cells), dtype=bool)
    membrane[model.blocks[1].elements] = True
    mesh = fem.Mesh(points, cells, "hexahedron")
    field = fem.FieldContainer([fem.Field(fem.RegionHexahedron(mesh), dim=3)])
    bodies = []
    for block, in_membrane in ((model.blocks[0], False), (model.blocks[1], True)):
        sub = fem.Mesh(points, cells[membrane == in_membrane], "hexahedron")
        f = fem.FieldContainer([fem.Field(fem.RegionHexahedron(sub), dim=3)])
        f.link(field)
        umat, mu0 = _ogden(block)
        bodies.append(fem.SolidBodyNearlyIncompressible(umat, f, bulk=bulk_ratio * mu0))
    return mesh, field, bodies, fem.RegionHexahedronBoundary


def _hex2_problem(fem, model, bulk_ratio, pressure_space):
    """The same for the 27-node hexahedron with the three-field (u, p, J) formulation."""
    points = model.mesh.p.T.copy()
    cells = vtk_cells(points, model.mesh.t.T)
    mesh8 = fem.Mesh(points, cells, "hexahedron")
    mesh = fem.mesh.convert(mesh8, order=2, calc_points=True, calc_midfaces=True,
                            calc_midvolumes=True)
    region = fem.RegionTriQuadraticHexahedron(mesh)
    displacement = fem.Field(region, dim=3)
    if pressure_space == "q1":
        duals = [fem.FieldDual(region, values=v) for v in (0.0, 1.0)]
    else:
        dual_mesh = mesh.dual(points_per_cell=4, disconnect=True)
        dual_region = fem.Region(dual_mesh, P1Disc(), region.quadrature, grad=False)
        # J_bar = 1 is the coefficient vector (1, 0, 0, 0) per element.
        j0 = np.zeros((len(dual_mesh.points), 1))
        j0[dual_mesh.cells[:, 0]] = 1.0
        duals = [fem.Field(dual_region, dim=1, values=0.0),
                 fem.Field(dual_region, dim=1, values=j0)]
    field = fem.FieldContainer([displacement, *duals])
    in_membrane = np.zeros(len(cells), dtype=bool)
    in_membrane[model.blocks[1].elements] = True
    masks = [~in_membrane, in_membrane]
    mats, bulk = [], np.zeros(len(cells))
    for block, mask in zip(model.blocks, masks):
        umat, mu0 = _ogden(block)
        mats.append(umat)
        bulk[mask] = bulk_ratio * mu0
    umat = fem.NearlyIncompressible(CellwiseMaterial(mats, masks), bulk=bulk)
    umat.chunksize = None   # all cells at once: the cell masks and bulk are per cell
    return mesh, field, [fem.SolidBody(umat, field)], fem.RegionTriQuadraticHexahedronBoundary


def felupe_curve(model: ActuatorModel, cavity_facets: np.ndarray, pressures_pa,
                 bulk_ratio: float, pressure_space: str = "p1"):
    """Angles (deg) at the given pressures with felupe, and the Newton iteration count."""
    import felupe as fem

    if model.settings.element == "hex1":
        mesh, field, bodies, boundary_region = _hex1_problem(fem, model, bulk_ratio)
    else:
        mesh, field, bodies, boundary_region = _hex2_problem(fem, model, bulk_ratio,
                                                             pressure_space)
    node = _node_map(mesh.points, model.doflocs)

    on_cavity = _on_chamber_walls(model.design, mesh.points)
    boundary = boundary_region(mesh, mask=on_cavity)
    n_faces = len(boundary.mesh.cells)
    if n_faces != len(cavity_facets):
        raise RuntimeError(f"felupe picked {n_faces} cavity faces, expected "
                           f"{len(cavity_facets)}")
    fb = fem.FieldContainer([fem.Field(boundary, dim=3)])
    fb.link(field)
    pressure = fem.SolidBodyPressure(fb)

    bcs = {"clamp": fem.Boundary(field[0], fx=0.0),
           "sym": fem.Boundary(field[0], fy=0.0, skip=(1, 0, 1))}
    angles, iterations = [], []

    def record(context, state):
        u = np.zeros((len(node), 3))
        u[node] = field[0].values
        angles.append(model.end_face_kinematics(u.ravel()[model.pattern.free])[0])
        iterations.append(context.substep.iterations)

    step = fem.Step(items=[*bodies, pressure], ramp={pressure: np.asarray(pressures_pa)},
                    boundaries=bcs)
    fem.Job(steps=[step], plugins=[record]).evaluate(x0=field, tol=1e-8, verbose=0)
    return np.array(angles), int(np.sum(iterations))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--element", choices=("hex1", "hex2"), default="hex1")
    ap.add_argument("--level", type=int, default=None,
                    help="mesh level (default: 1 for hex1, 0 for hex2)")
    ap.add_argument("--pressure-space", choices=("p1", "q1"), default="p1",
                    help="hex2 only: felupe's pressure / dilatation space")
    ap.add_argument("--pmax", type=float, default=1500.0)
    ap.add_argument("--dp", type=float, default=100.0)
    ap.add_argument("--bulk-ratio", type=float, default=1000.0)
    args = ap.parse_args()
    level = args.level if args.level is not None else (1 if args.element == "hex1" else 0)
    pressures = np.arange(args.dp, args.pmax + 0.5 * args.dp, args.dp)
    settings = SolverSettings(mesh_level=level, element=args.element, control="pressure",
                              bulk_ratio=args.bulk_ratio)
    model = ActuatorModel(Design(), settings)
    space = f", felupe pressure space {args.pressure_space}" if args.element == "hex2" else ""
    print(f"standard design, {args.element}, mesh level {level}: {model.n_free} free dofs, "
          f"K = {args.bulk_ratio} mu0, {len(pressures)} pressure increments of {args.dp} Pa"
          f"{space}")

    t0, c0 = time.perf_counter(), time.process_time()
    out = drive_pressure(model, pressures, settings)
    t_ours, c_ours = time.perf_counter() - t0, time.process_time() - c0
    ours = np.array([model.end_face_kinematics(u)[0] for u, _ in out])
    its_ours = sum(i for _, i in out)

    t0, c0 = time.perf_counter(), time.process_time()
    facets = build_mesh(model.design, level).cavity_facets
    theirs, its_felupe = felupe_curve(model, facets, pressures, args.bulk_ratio,
                                      args.pressure_space)
    t_felupe, c_felupe = time.perf_counter() - t0, time.process_time() - c0

    print(f"{'p (Pa)':>8} {'ours (deg)':>11} {'felupe (deg)':>13} {'diff (%)':>9}")
    for p, a, b in zip(pressures, ours, theirs):
        print(f"{p:8.0f} {a:11.5f} {b:13.5f} {100 * (a / b - 1):+9.4f}")
    for target in (10.0, 20.0, 30.0):
        if ours[-1] >= target and theirs[-1] >= target:
            p_ours = float(np.interp(target, ours, pressures))
            p_theirs = float(np.interp(target, theirs, pressures))
            print(f"p at {target:.0f} deg (linear interpolation): ours {p_ours:.1f} Pa, "
                  f"felupe {p_theirs:.1f} Pa ({100 * (p_ours / p_theirs - 1):+.3f} %)")
    print(f"wall time: ours {t_ours:.1f} s ({its_ours} Newton iterations, "
          f"{model.timings}), felupe {t_felupe:.1f} s ({its_felupe} iterations), "
          f"ratio {t_felupe / t_ours:.1f}")
    print(f"CPU time of this process (a fairer ratio on a loaded machine): ours "
          f"{c_ours:.1f} s, felupe {c_felupe:.1f} s, ratio {c_felupe / c_ours:.1f}")


if __name__ == "__main__":
    main()
