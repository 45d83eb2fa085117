"""The former and the balanced level 0 on a random sample of a database's designs.

For each sampled record (its design and settings, the tip included), the curve is solved
again on both meshes, one after the other in this process: wall time, status, end angle,
and the pressure at 10 / 30 / 60 deg (free tips; PCHIP above 2 deg) or the force at the
end pressure (blocked tips) of the balanced mesh relative to the former. The ratio of
the summed wall times is the cost of rebuilding the database on the balanced mesh.

    OMP_NUM_THREADS=1 python benchmarks/mesh_switch_sample.py --n 16 --seed 1
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace

import numpy as np
from compare_rebuild import pressure_at

from solver.stepping import solve
from solver.store import CurveStore


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--db", default="service/data/curves.h5")
    ap.add_argument("--n", type=int, default=16)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    with CurveStore(args.db) as db:
        keys = sorted(db.keys())
        rng = np.random.default_rng(args.seed)
        chosen = rng.choice(len(keys), size=args.n, replace=False)
        records = [db.get(keys[i]) for i in chosen]
    totals = {"former": 0.0, "balanced": 0.0}
    for rec in records:
        row = {"key": rec.key[:12], "tip": rec.settings.tip,
               "pair": f"{rec.design.body_material.id}/{rec.design.membrane_material.id}",
               "L_t_T_b_h_mm": [rec.design.L_mm, rec.design.t_mm, rec.design.T_mm,
                                rec.design.b_mm, rec.design.h_mm]}
        curves = {}
        for mesh in ("former", "balanced"):
            t0 = time.perf_counter()
            c = solve(rec.design, replace(rec.settings, mesh_divisions=mesh))
            wall = time.perf_counter() - t0
            totals[mesh] += wall
            curves[mesh] = c
            row[mesh] = {"dofs": int(c.n_dofs), "wall_s": round(wall, 1), "status": c.status,
                         "end_angle_deg": round(float(c.angle_deg[-1]), 1),
                         "end_pressure_pa": round(float(c.pressure_pa[-1]))}
        if rec.settings.tip == "free":
            angles = (10.0, 30.0, 60.0)
            p_def = pressure_at(curves["former"], angles)
            p_bal = pressure_at(curves["balanced"], angles)
            n = len(angles)
            row["p_balanced_over_former_pct"] = dict(zip(
                [f"{a:g}deg" for a in angles[:n]],
                np.round(100 * (p_bal[:n] / p_def[:n] - 1), 2).tolist(), strict=True))
        else:
            f_end = float(np.interp(curves["former"].pressure_pa[-1],
                                    curves["balanced"].pressure_pa,
                                    curves["balanced"].force_mn))
            row["force_balanced_over_former_pct"] = round(
                100 * (f_end / float(curves["former"].force_mn[-1]) - 1), 2)
        print(json.dumps(row), flush=True)
    print(json.dumps({"total_wall_s": {k: round(v, 1) for k, v in totals.items()},
                      "balanced_over_former": round(totals["balanced"] / totals["former"], 3)}))


if __name__ == "__main__":
    main()
