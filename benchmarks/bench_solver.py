"""Benchmark: the full standard-design curve (0 to 90 deg) with the FE solver.

Reports DOFs, steps, Newton iterations, cut-backs, time per iteration split into
assembly and linear solve, wall time and peak memory, for each linear-solver backend
available (SuperLU always; MKL PARDISO, installed by default on x86_64).

    python benchmarks/bench_solver.py [--mesh LEVEL] [--element hex2] [--max-angle-deg 90]
    python benchmarks/bench_solver.py --corners    # corners of the database's design box
    python benchmarks/bench_solver.py --divisions balanced [--corners]   # a named level 0

``--corners``: the default settings on designs at the corners of the box the curve
database spans (L 4-18 mm, t 0.5-1.2, T 0.6-2.0, b 1.0-2.4, h 0.10-0.30, W = 3; the
four material pairs; each layer's mu scaled 0.5-2), free tip to 90 deg and a blocked
tip: wall time, steps, iterations, end status per design.
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import time

import numpy as np

from solver import Design, SolverSettings
from solver.linear import available_backends
from solver.materials import MATERIALS, OgdenMaterial
from solver.mesh import DEFAULT_DIVISIONS, NAMED_DIVISIONS, MeshDivisions, xz_family
from solver.stepping import solve


def run(level: int, element: str, max_angle: float, backend: str,
        divisions: MeshDivisions = DEFAULT_DIVISIONS) -> dict:
    settings = SolverSettings(mesh_level=level, element=element, max_angle_deg=max_angle)
    t0 = time.perf_counter()
    curve = solve(Design(), settings, backend=backend, divisions=divisions)
    wall = time.perf_counter() - t0
    its = int(curve.newton_iterations.sum())
    steps = len(curve) - 1
    # Each step also evaluates the converged state once (without tangent) for the outputs.
    t = curve.timings_s
    return {
        "backend": backend, "mesh_level": level, "element": element, "dofs": curve.n_dofs,
        "status": curve.status, "final_angle_deg": round(float(curve.angle_deg[-1]), 2),
        "final_pressure_pa": round(float(curve.pressure_pa[-1]), 1), "steps": steps,
        "newton_iterations": its, "cutbacks": int(t.get("cutbacks", 0)),
        "factorisations": int(t.get("factorisations", 0)),
        "tangent_evaluations": int(t.get("tangent_evaluations", 0)),
        "residual_evaluations": int(t.get("residual_evaluations", 0)),
        "other_s": round(wall - t["assembly_s"] - t["linear_solve_s"], 2),   # set-up, output
        "wall_s": round(wall, 1),
        "assembly_s_per_iteration": round(t["assembly_s"] / max(its, 1), 3),
        "linear_solve_s_per_iteration": round(t["linear_solve_s"] / max(its, 1), 3),
        "pressure_at_30_60_deg_pa": [round(float(np.interp(a, curve.angle_deg,
                                                             curve.pressure_pa)), 1)
                                     for a in (30, 60)],
    }


def scaled(material_id: str, factor: float) -> OgdenMaterial:
    """A preset with every Ogden mu scaled by ``factor`` (the database's mu range)."""
    m = MATERIALS[material_id]
    return OgdenMaterial(f"{material_id}_x{factor:g}", tuple(factor * x for x in m.mu_kpa),
                         m.alpha)


def corner_cases() -> list[tuple[str, Design, SolverSettings]]:
    stiff_short = dict(L_mm=4.0, t_mm=1.2, T_mm=2.0, b_mm=1.0, h_mm=0.1)
    soft_long = dict(L_mm=18.0, t_mm=0.5, T_mm=0.6, b_mm=2.4, h_mm=0.3)
    free, blocked = SolverSettings(), SolverSettings(tip="blocked")
    pdms, eco, pdms15 = MATERIALS["pdms_1_10"], MATERIALS["ecoflex_00_30"], MATERIALS["pdms_1_15"]
    return [
        ("stiff-short pdms_1_10/eco", Design(**stiff_short), free),
        ("soft-long pdms_1_10/eco", Design(**soft_long), free),
        ("stiff-short pdms_1_15/eco body mu x2, membrane mu x0.5",
         Design(**stiff_short, body_material=scaled("pdms_1_15", 2.0),
                membrane_material=scaled("ecoflex_00_30", 0.5)), free),
        ("soft-long eco/pdms_1_15 (reversed)",
         Design(**soft_long, body_material=eco, membrane_material=pdms15), free),
        ("soft-long eco/eco", Design(**soft_long, body_material=eco, membrane_material=eco),
         free),
        ("standard design, blocked tip", Design(), blocked),
        ("stiff-short pdms_1_10/eco, blocked tip", Design(**stiff_short, body_material=pdms),
         blocked),
    ]


def run_corners(divisions: MeshDivisions = DEFAULT_DIVISIONS) -> None:
    for name, design, settings in corner_cases():
        t0 = time.perf_counter()
        curve = solve(design, settings, divisions=divisions)
        t = curve.timings_s
        print(json.dumps({
            "case": name, "status": curve.status, "reason": curve.reason,
            "dofs": curve.n_dofs, "steps": len(curve) - 1,
            "newton_iterations": int(curve.newton_iterations.sum()),
            "factorisations": int(t.get("factorisations", 0)),
            "cutbacks": int(t.get("cutbacks", 0)),
            "wall_s": round(time.perf_counter() - t0, 1),
            "final_angle_deg": round(float(curve.angle_deg[-1]), 2),
            "final_pressure_pa": round(float(curve.pressure_pa[-1]), 1),
            "final_force_mn": round(float(curve.force_mn[-1]), 4),
            "max_volume_control_unstable_modes": int(
                np.max(curve.volume_control_negative_eigenvalues)),
        }), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", type=int, default=SolverSettings().mesh_level)
    ap.add_argument("--element", default="hex2")
    ap.add_argument("--max-angle-deg", type=float, default=90.0)
    ap.add_argument("--backends", nargs="*", default=None)
    ap.add_argument("--corners", action="store_true", help="the design box's corners")
    ap.add_argument("--former-mesh", action="store_true",
                    help="the former default level 0 (before issue 12), for speed comparisons")
    ap.add_argument("--divisions", choices=tuple(NAMED_DIVISIONS),
                    default=SolverSettings().mesh_divisions,
                    help="a named level-0 resolution (solver/mesh.py)")
    args = ap.parse_args()
    divisions = NAMED_DIVISIONS[args.divisions]
    print(f"# machine: {platform.processor() or platform.machine()}, "
          f"{platform.python_version()}, numpy {np.__version__}")
    if args.corners:
        run_corners(divisions)
        return
    for backend in args.backends or available_backends():
        result = run(args.mesh, args.element, args.max_angle_deg, backend,
                     xz_family(1) if args.former_mesh else divisions)
        result["divisions"] = "former" if args.former_mesh else args.divisions
        result["peak_rss_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
        print(json.dumps(result))


if __name__ == "__main__":
    main()
