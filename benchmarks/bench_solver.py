"""Benchmark: the full standard-design curve (0 to 90 deg) with the FE solver.

Reports DOFs, steps, Newton iterations, cut-backs, time per iteration split into
assembly and linear solve, wall time and peak memory, for each linear-solver backend
available (SuperLU always; MKL PARDISO, installed by default on x86_64).

    python benchmarks/bench_solver.py [--mesh LEVEL] [--element hex2] [--max-angle-deg 90]
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
from solver.stepping import solve


def run(level: int, element: str, max_angle: float, backend: str) -> dict:
    settings = SolverSettings(mesh_level=level, element=element, max_angle_deg=max_angle)
    t0 = time.perf_counter()
    curve = solve(Design(), settings, backend=backend)
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
        "wall_s": round(wall, 1),
        "assembly_s_per_iteration": round(t["assembly_s"] / max(its, 1), 3),
        "linear_solve_s_per_iteration": round(t["linear_solve_s"] / max(its, 1), 3),
        "pressure_at_30_60_deg_pa": [round(float(np.interp(a, curve.angle_deg,
                                                             curve.pressure_pa)), 1)
                                     for a in (30, 60)],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", type=int, default=SolverSettings().mesh_level)
    ap.add_argument("--element", default="hex2")
    ap.add_argument("--max-angle-deg", type=float, default=90.0)
    ap.add_argument("--backends", nargs="*", default=None)
    args = ap.parse_args()
    print(f"# machine: {platform.processor() or platform.machine()}, "
          f"{platform.python_version()}, numpy {np.__version__}")
    for backend in args.backends or available_backends():
        result = run(args.mesh, args.element, args.max_angle_deg, backend)
        result["peak_rss_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
        print(json.dumps(result))


if __name__ == "__main__":
    main()
