"""Cross-check of the FE solver against felupe on the standard actuator.

Same geometry and mesh (``solver.mesh.build_mesh``'s points and Hex1 cells), same
materials (the paper's Ogden sets; felupe's Ogden form is sum 2 mu_f / alpha^2 (...),
so mu_f = mu alpha / 2), same bulk modulus (K = bulk_ratio x mu0 per material), same
element technology (Hex1 with a constant pressure / mean dilatation per element,
felupe's SolidBodyNearlyIncompressible), same boundary conditions (clamped x = 0,
symmetry y = 0), follower pressure on the chamber walls, pressure control with the
same increments. Both codes' wall times are measured in the same run.

    .venv/bin/python benchmarks/bench_felupe.py [--level 1] [--pmax 1500] [--dp 100]

felupe is an optional benchmark extra (pyproject ``benchmark``); results are
recorded in benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from solver import Design, SolverSettings
from solver.mesh import build_mesh
from solver.model import ActuatorModel
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


def felupe_curve(model: ActuatorModel, cavity_facets: np.ndarray, pressures_pa,
                 bulk_ratio: float):
    """Angles (deg) at the given pressures with felupe, and the Newton iteration count."""
    import felupe as fem
    import felupe.constitution.tensortrax as mat

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
        mu_f = list(block.mu_pa * block.alpha / 2.0)
        umat = mat.Hyperelastic(mat.models.hyperelastic.ogden, mu=mu_f,
                                alpha=list(block.alpha))
        bulk = bulk_ratio * float(sum(mu_f))
        bodies.append(fem.SolidBodyNearlyIncompressible(umat, f, bulk=bulk))

    on_cavity = np.zeros(len(points), dtype=bool)
    on_cavity[model.mesh.facets[:, cavity_facets]] = True
    boundary = fem.RegionHexahedronBoundary(mesh, mask=on_cavity)
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
        substep = context.substep
        u = field[0].values.ravel()
        angles.append(model.end_face_kinematics(u[model.pattern.free])[0])
        iterations.append(substep.iterations)

    step = fem.Step(items=[*bodies, pressure], ramp={pressure: np.asarray(pressures_pa)},
                    boundaries=bcs)
    fem.Job(steps=[step], plugins=[record]).evaluate(x0=field, tol=1e-8, verbose=0)
    return np.array(angles), int(np.sum(iterations))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--level", type=int, default=1)
    ap.add_argument("--pmax", type=float, default=1500.0)
    ap.add_argument("--dp", type=float, default=100.0)
    ap.add_argument("--bulk-ratio", type=float, default=1000.0)
    args = ap.parse_args()
    pressures = np.arange(args.dp, args.pmax + 0.5 * args.dp, args.dp)
    settings = SolverSettings(mesh_level=args.level, element="hex1", control="pressure",
                              bulk_ratio=args.bulk_ratio)
    model = ActuatorModel(Design(), settings)
    print(f"standard design, hex1, mesh level {args.level}: {model.n_free} free dofs, "
          f"K = {args.bulk_ratio} mu0, {len(pressures)} pressure increments of {args.dp} Pa")

    t0 = time.perf_counter()
    out = drive_pressure(model, pressures, settings)
    t_ours = time.perf_counter() - t0
    ours = np.array([model.end_face_kinematics(u)[0] for u, _ in out])
    its_ours = sum(i for _, i in out)

    t0 = time.perf_counter()
    facets = build_mesh(model.design, args.level).cavity_facets
    theirs, its_felupe = felupe_curve(model, facets, pressures, args.bulk_ratio)
    t_felupe = time.perf_counter() - t0

    print(f"{'p (Pa)':>8} {'ours (deg)':>11} {'felupe (deg)':>13} {'diff (%)':>9}")
    for p, a, b in zip(pressures, ours, theirs):
        print(f"{p:8.0f} {a:11.3f} {b:13.3f} {100 * (a / b - 1):+9.2f}")
    print(f"wall time: ours {t_ours:.1f} s ({its_ours} Newton iterations, "
          f"{model.timings}), felupe {t_felupe:.1f} s ({its_felupe} iterations)")


if __name__ == "__main__":
    main()
