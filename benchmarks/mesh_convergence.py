"""Mesh-convergence study of the standard design (Table 3), hex2 elements.

For each mesh level: the pressure at which the curve reaches 30 and 60 deg, and the angle
at fixed pressures. Level n has n + 1 times the divisions of level 0 in every direction
(solver/mesh.py), so the element size is h = 1 / (n + 1) of level 0's and any three
levels give the observed order q and a Richardson estimate; two levels give the
estimate for an assumed q.
Writes JSON per level to OUTDIR and a plot docs/verification-convergence.png.

    python benchmarks/mesh_convergence.py --family coarse --levels 0 1 2 --outdir out/coarse
    python benchmarks/mesh_convergence.py --levels 0 1 --outdir out/convergence
    python benchmarks/mesh_convergence.py --plot-only --outdir out/convergence
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from solver.mesh import COARSE_DIVISIONS, DEFAULT_DIVISIONS, xz_family
from solver.verification.richardson import observed_order, richardson

PAPER_A, PAPER_TAU_PA = 0.704, 420.0   # the paper's fit of the standard design (Table 4)
# "default": the product's levels; "coarse": the uniform family of the previous level 0
# (half the divisions across the chamber width and through the membrane), whose three
# cheap levels give the observed order.
# "xz1".."xz3": the x-and-layers family of issue 12 (solver.mesh.xz_family; run each at
# --levels 0, the member number is the refinement): the reference of the default level 0.
FAMILIES = {"default": DEFAULT_DIVISIONS, "coarse": COARSE_DIVISIONS,
            **{f"xz{r}": xz_family(r) for r in (1, 2, 3)}}


def run_level(level: int, outdir: Path, max_angle: float, backend: str, family: str) -> dict:
    from solver import Design, SolverSettings
    from solver.stepping import solve

    t0 = time.perf_counter()
    c = solve(Design(), SolverSettings(mesh_level=level, element="hex2",
                                       max_angle_deg=max_angle), backend=backend,
              divisions=FAMILIES[family])
    data = {"level": level, "family": family, "dofs": c.n_dofs,
            "wall_s": time.perf_counter() - t0,
            "status": c.status, "pressure_pa": c.pressure_pa.tolist(),
            "angle_deg": c.angle_deg.tolist(), "iterations": int(c.newton_iterations.sum()),
            "backend": backend}
    (outdir / f"level{level}.json").write_text(json.dumps(data))
    return data


def _p_at(run: dict, angles: list[float]) -> np.ndarray:
    """Pressure at the given angles: PCHIP through the converged points above 2 deg
    (monotone there; below, the transition regime makes the angle non-monotone)."""
    from scipy.interpolate import PchipInterpolator

    a, p = np.asarray(run["angle_deg"]), np.asarray(run["pressure_pa"])
    keep = a > 2.0
    return PchipInterpolator(a[keep], p[keep])(angles)


def summarise(runs: list[dict]) -> None:
    pressures = [1500.0, 1740.0, 2000.0]
    print("level  dofs   p@30deg  p@60deg  " + "  ".join(f"a@{p:.0f}Pa" for p in pressures))
    for r in runs:
        pa = _p_at(r, [30, 60])
        aa = np.interp(pressures, r["pressure_pa"], r["angle_deg"])
        print(f"{r['level']:5d} {r['dofs']:6d} {pa[0]:8.1f} {pa[1]:8.1f}  "
              + "  ".join(f"{a:8.2f}" for a in aa))
    if len(runs) < 2:
        return
    h = np.array([1.0 / (r["level"] + 1) for r in runs])
    for k, angle in enumerate((30, 60)):
        f = np.array([_p_at(r, [30, 60])[k] for r in runs])
        q_obs = observed_order(h[-3:], f[-3:]) if len(runs) >= 3 else None
        orders = ([("observed", q_obs)] if q_obs is not None else []) + [("assumed", 2.0),
                                                                         ("assumed", 1.0)]
        for label, q in orders:
            extrap = richardson(h, f, q)
            errs = ", ".join(f"level {r['level']}: {100 * (fi / extrap - 1):+.2f} %"
                             for r, fi in zip(runs, f))
            print(f"p@{angle}deg, q = {q:.2f} ({label}): extrapolated {extrap:.1f} Pa; {errs}")
        if len(runs) >= 3 and q_obs is None:
            print(f"p@{angle}deg: the three finest levels are not monotone (no observed order)")


def plot(runs: list[dict], path: Path) -> None:
    """Curves of every run (left) and p at 30 / 60 deg against dofs per family (right)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    for r in runs:
        style = "o-" if r.get("family", "default") == "default" else "s--"
        ax.plot(r["pressure_pa"], r["angle_deg"], style, ms=2,
                label=f"{r.get('family', 'default')} level {r['level']} ({r['dofs']} dofs)")
    p = np.linspace(0, 2100, 200)
    ax.plot(p, PAPER_A * (np.exp(p / PAPER_TAU_PA) - 1), "k:",
            label="paper's fit 0.704 (exp(p/420) - 1)")
    ax.set_xlabel("pressure (Pa)")
    ax.set_ylabel("bending angle (deg)")
    ax.set_ylim(-2, 70)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("Standard design (Table 3), hex2")
    for family, marker in (("default", "o"), ("coarse", "s")):
        fam = [r for r in runs if r.get("family", "default") == family]
        if not fam:
            continue
        dofs = [r["dofs"] for r in fam]
        for k, angle in enumerate((30, 60)):
            bx.semilogx(dofs, [_p_at(r, [30, 60])[k] for r in fam], marker + "-",
                        label=f"{family}: p at {angle} deg")
    bx.set_xlabel("free dofs (half model)")
    bx.set_ylabel("pressure (Pa)")
    bx.grid(alpha=0.3, which="both")
    bx.legend(fontsize=7)
    bx.set_title("Convergence of the pressure for a given angle")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=int, nargs="*", default=[0, 1, 2])
    ap.add_argument("--outdir", type=Path, default=Path("out/convergence"))
    ap.add_argument("--max-angle-deg", type=float, default=65.0)
    ap.add_argument("--backend", default="auto", help="linear solver: auto, superlu or pardiso")
    ap.add_argument("--family", choices=sorted(FAMILIES), default="default",
                    help="mesh family: the product's levels, or the uniform coarse one")
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--compare", type=Path, nargs="*", default=[],
                    help="other studies' OUTDIRs to draw in the same plot")
    ap.add_argument("--plot", type=Path, default=Path("docs/verification-convergence.png"))
    args = ap.parse_args()
    args.outdir.mkdir(parents=True, exist_ok=True)
    if not args.plot_only:
        for level in args.levels:
            run_level(level, args.outdir, args.max_angle_deg, args.backend, args.family)
    runs = sorted((json.loads(p.read_text()) for p in args.outdir.glob("level*.json")),
                  key=lambda r: r["level"])
    summarise(runs)
    others = [json.loads(p.read_text()) for d in args.compare for p in d.glob("level*.json")]
    plot(runs + others, args.plot)


if __name__ == "__main__":
    main()
