"""Level-0 mesh candidates of the standard design against its mesh-extrapolated curve.

Each candidate (solver.mesh.MeshDivisions) is solved to 65 deg (hex2, volume control)
and read off as in tests/test_solver_convergence.py: the pressure at 10 / 30 / 60 deg
(PCHIP through the points above 2 deg) and the angle at 1000-2000 Pa (PCHIP through the
points above 300 Pa), each as a per-cent error against the three-level extrapolation of
the x-and-layers family (observed order 2.3-2.8; docs/verification.md, "The default level
0"). One JSON line per candidate: dofs, wall time, Newton iterations, the errors.

    OMP_NUM_THREADS=1 python benchmarks/mesh_candidates.py              # all candidates
    OMP_NUM_THREADS=1 python benchmarks/mesh_candidates.py balanced default
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace

import numpy as np
from scipy.interpolate import PchipInterpolator

from solver import Design, SolverSettings
from solver.mesh import BALANCED_DIVISIONS, FINE_X_DIVISIONS, FORMER_DIVISIONS
from solver.stepping import solve

# The extrapolated standard-design curve (docs/verification.md, "extrapolated (observed
# order)" row: members r = 1, 2, 3 of solver.mesh.xz_family).
ANGLES_DEG = (10.0, 30.0, 60.0)
PRESSURE_REF_PA = np.array([1223.6, 1711.9, 1992.3])
PRESSURES_PA = (1000.0, 1250.0, 1500.0, 1750.0, 2000.0)
ANGLE_REF_DEG = np.array([5.879, 10.620, 18.605, 32.764, 61.325])

D = FORMER_DIVISIONS
CANDIDATES = {
    "former": D,
    "chamber_graded4": replace(D, x_chamber_grading=4.0),
    "chamber_graded6": replace(D, x_chamber_grading=6.0),
    "chamber2": replace(D, chamber=2),
    "body3": replace(D, body=3),
    "chamber_graded6_chamber2": replace(D, x_chamber_grading=6.0, chamber=2),
    "chamber_graded6_chamber2_x1.25": replace(D, x_chamber_grading=6.0, chamber=2,
                                              x_chamber_mm=1.25),
    "chamber_graded3_chamber2": replace(D, x_chamber_grading=3.0, chamber=2),
    "wall3": replace(D, x_wall_grading=3.0),
    "wall5": replace(D, x_wall_grading=5.0),
    "wall3_chamber2": replace(D, x_wall_grading=3.0, chamber=2),
    "wall5_chamber2_x1.25": replace(D, x_wall_grading=5.0, chamber=2, x_chamber_mm=1.25),
    "balanced": BALANCED_DIVISIONS,
    "balanced_x1.25": replace(BALANCED_DIVISIONS, x_chamber_mm=1.25),
    "balanced_wall2.5": replace(BALANCED_DIVISIONS, x_wall_grading=2.5),
    "fine_x": FINE_X_DIVISIONS,
}


def errors_pct(design: Design, divisions) -> dict:
    t0 = time.perf_counter()
    c = solve(design, SolverSettings(max_angle_deg=65), divisions=divisions)
    wall = time.perf_counter() - t0
    keep = c.angle_deg > 2.0
    p = PchipInterpolator(c.angle_deg[keep], c.pressure_pa[keep])(ANGLES_DEG)
    keep = c.pressure_pa > 300.0
    a = PchipInterpolator(c.pressure_pa[keep], c.angle_deg[keep])(PRESSURES_PA)
    return {"dofs": int(c.n_dofs), "wall_s": round(wall, 1), "status": c.status,
            "newton_iterations": int(c.newton_iterations.sum()),
            "p_err_pct_10_30_60_deg": np.round(100 * (p / PRESSURE_REF_PA - 1), 2).tolist(),
            "angle_err_pct_1000_2000_pa": np.round(100 * (a / ANGLE_REF_DEG - 1), 2).tolist()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", metavar="NAME",
                    help="candidates to run (default: all): " + ", ".join(CANDIDATES))
    args = ap.parse_args()
    unknown = sorted(set(args.names) - set(CANDIDATES))
    if unknown:
        ap.error(f"unknown candidate {unknown[0]!r} (allowed: {', '.join(CANDIDATES)})")
    for name in args.names or CANDIDATES:
        print(json.dumps({"candidate": name, **errors_pct(Design(), CANDIDATES[name])}),
              flush=True)


if __name__ == "__main__":
    main()
