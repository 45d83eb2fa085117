"""Mesh-convergence study of the standard design (Table 3), hex2 elements.

For each mesh level: the pressure at which the curve reaches 30 and 60 deg, and the angle
at fixed pressures; two-level Richardson estimates (levels n and n + 2, assumed orders 1
and 2) when such a pair exists.
Writes JSON per level to OUTDIR and a plot docs/verification-convergence.png.

    python benchmarks/mesh_convergence.py --levels 0 1 2 --outdir out/convergence
    python benchmarks/mesh_convergence.py --plot-only --outdir out/convergence
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

PAPER_A, PAPER_TAU_PA = 0.704, 420.0   # the paper's fit of the standard design (Table 4)


def run_level(level: int, outdir: Path, max_angle: float, backend: str) -> dict:
    from solver import Design, SolverSettings
    from solver.stepping import solve

    t0 = time.perf_counter()
    c = solve(Design(), SolverSettings(mesh_level=level, element="hex2",
                                       max_angle_deg=max_angle), backend=backend)
    data = {"level": level, "dofs": c.n_dofs, "wall_s": time.perf_counter() - t0,
            "status": c.status, "pressure_pa": c.pressure_pa.tolist(),
            "angle_deg": c.angle_deg.tolist(), "iterations": int(c.newton_iterations.sum()),
            "backend": backend}
    (outdir / f"level{level}.json").write_text(json.dumps(data))
    return data


def summarise(runs: list[dict]) -> None:
    pressures = [1500.0, 1740.0, 2000.0]
    print("level  dofs   p@30deg  p@60deg  " + "  ".join(f"a@{p:.0f}Pa" for p in pressures))
    for r in runs:
        pa = np.interp([30, 60], r["angle_deg"], r["pressure_pa"])
        aa = np.interp(pressures, r["pressure_pa"], r["angle_deg"])
        print(f"{r['level']:5d} {r['dofs']:6d} {pa[0]:8.1f} {pa[1]:8.1f}  "
              + "  ".join(f"{a:8.2f}" for a in aa))
    by_level = {r["level"]: r for r in runs}
    for lo in sorted(by_level):
        if lo + 2 not in by_level:
            continue
        # Levels n and n + 2 halve the element size in every direction (the odd levels
        # round some divisions down, so three consecutive levels are not a geometric
        # sequence): two-level Richardson with an assumed order q.
        f0, f2 = (np.interp([30, 60], by_level[k]["angle_deg"], by_level[k]["pressure_pa"])
                  for k in (lo, lo + 2))
        for q in (2.0, 1.0):
            extrap = f2 + (f2 - f0) / (2.0**q - 1.0)
            errs = {k: 100 * (np.interp([30, 60], r["angle_deg"], r["pressure_pa"]) / extrap - 1)
                    for k, r in sorted(by_level.items())}
            print(f"levels {lo},{lo + 2}, q = {q:.0f}: extrapolated p@30,60 = "
                  f"{extrap.round(1)}; error % per level: "
                  + ", ".join(f"{k}: {e.round(1)}" for k, e in errs.items()))


def plot(runs: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for r in runs:
        ax.plot(r["pressure_pa"], r["angle_deg"], "o-", ms=2,
                label=f"hex2 level {r['level']} ({r['dofs']} dofs)")
    p = np.linspace(0, 2100, 200)
    ax.plot(p, PAPER_A * (np.exp(p / PAPER_TAU_PA) - 1), "k--",
            label="paper's fit 0.704 (exp(p/420) - 1)")
    ax.set_xlabel("pressure (Pa)")
    ax.set_ylabel("bending angle (deg)")
    ax.set_ylim(-2, 95)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Standard design: mesh convergence and the paper's fit")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=int, nargs="*", default=[0, 1, 2])
    ap.add_argument("--outdir", type=Path, default=Path("out/convergence"))
    ap.add_argument("--max-angle-deg", type=float, default=65.0)
    ap.add_argument("--backend", default="superlu", help="linear solver: superlu or pardiso")
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--plot", type=Path, default=Path("docs/verification-convergence.png"))
    args = ap.parse_args()
    args.outdir.mkdir(parents=True, exist_ok=True)
    if not args.plot_only:
        for level in args.levels:
            run_level(level, args.outdir, args.max_angle_deg, args.backend)
    runs = [json.loads(p.read_text()) for p in sorted(args.outdir.glob("level*.json"))]
    summarise(runs)
    plot(runs, args.plot)


if __name__ == "__main__":
    main()
