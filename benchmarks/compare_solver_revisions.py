"""Benchmark: the solver at a git revision against the working tree, in CPU time.

For speed-only changes on a loaded machine: wall times there mean little, so both versions
are timed by the CPU time of their process (one thread), and compared in one run.

    OMP_NUM_THREADS=1 python benchmarks/compare_solver_revisions.py REV [--curves N]

- unit costs, alternating in one process at the 30-degree state of the standard design
  (the revision's ``solver/`` exported with ``git archive`` and imported as ``solver_base``):
  model set-up, tangent and residual-only evaluation, PARDISO factorisation and solve;
- ``--curves N``: N full standard curves per version, alternating, one process each
  (``solve(Design(), SolverSettings())``): CPU and wall time, counts, p at 30 / 60 deg,
  peak RSS; ``--threads T`` runs them with OMP_NUM_THREADS = MKL_NUM_THREADS = T (a
  wall-clock comparison on a quiet machine), ``--no-units`` skips the unit costs.

Results are recorded in benchmarks/RESULTS.md (issue 12, third to fifth sessions).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]

CURVE = """
import json, os, resource, time
import numpy as np
from solver import Design, SolverSettings
from solver.stepping import solve
def peak_rss_mb():
    # VmHWM: this process image's own peak (ru_maxrss also counts the pages the parent
    # had when it forked this child, e.g. after the unit costs' two models).
    try:
        with open("/proc/self/status") as f:
            kb = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
    except (OSError, StopIteration):
        kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return round(kb / 1024)
t0, w0 = time.process_time(), time.perf_counter()
c = solve(Design(), SolverSettings())
t = c.timings_s
print(json.dumps({"cpu_s": round(time.process_time() - t0, 2),
    "wall_s": round(time.perf_counter() - w0, 2), "steps": len(c) - 1,
    "solves": int(c.newton_iterations.sum()), "tangents": t.get("tangent_evaluations"),
    "residuals": t.get("residual_evaluations"), "factorisations": t.get("factorisations"),
    "cutbacks": t.get("cutbacks", 0), "landing_steps": t.get("landing_steps", 0),
    "end_angle_deg": float(c.angle_deg[-1]), "end_volume_ul": float(c.volume_ul[-1]),
    "peak_rss_mb": peak_rss_mb(),
    "p_at_30_60_deg_pa": [float(np.interp(a, c.angle_deg, c.pressure_pa)) for a in (30, 60)]}))
np.savez(os.environ["CURVE_FILE"], volume_ul=c.volume_ul, pressure_pa=c.pressure_pa,
         angle_deg=c.angle_deg)
"""


def export(rev: str, into: pathlib.Path) -> pathlib.Path:
    """The revision's solver/ package as ``solver_base`` under ``into`` (a tree for
    PYTHONPATH as ``solver`` too, under ``into/tree``)."""
    tree = into / "tree"
    tree.mkdir()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "solver"],
                             check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    renamed = into / "renamed" / "solver_base"
    for path in (tree / "solver").rglob("*.py"):
        target = renamed / path.relative_to(tree / "solver")
        target.parent.mkdir(parents=True, exist_ok=True)
        text = re.sub(r"\bfrom solver(\.| import)", r"from solver_base\1", path.read_text())
        target.write_text(re.sub(r"\bimport solver\.", "import solver_base.", text))
    return tree


def unit_costs(renamed_parent: pathlib.Path, repeats: int = 8) -> None:
    sys.path.insert(0, str(renamed_parent))
    import solver_base.linear as base_linear
    try:                                    # solver/model.py was renamed discrete.py
        import solver_base.discrete as base_model
    except ImportError:
        import solver_base.model as base_model
    from solver_base import Design as BaseDesign
    from solver_base import SolverSettings as BaseSettings

    import solver.discrete as new_model
    import solver.linear as new_linear
    from solver import Design, SolverSettings
    from solver.stepping import inflate

    curve, model, u = inflate(Design(), SolverSettings(max_angle_deg=30.0))
    q, p = model.consistent_pressures(u), float(curve.pressure_pa[-1])
    times: dict[str, list[float]] = {}

    def clock(key, f, *args, **kwargs):
        t0 = time.process_time()
        out = f(*args, **kwargs)
        times.setdefault(key, []).append(time.process_time() - t0)
        return out

    models = {}
    for _ in range(3):
        models["before"] = clock("set-up before", base_model.ActuatorModel, BaseDesign(),
                                 BaseSettings())
        models["after"] = clock("set-up after", new_model.ActuatorModel, Design(),
                                SolverSettings())
    linear = {"before": base_linear, "after": new_linear}
    for _ in range(repeats):
        for tag in ("before", "after"):
            m = models[tag]
            ev = clock(f"tangent evaluation {tag}", m.evaluate, u, p, pressures=q)
            clock(f"residual evaluation {tag}", m.evaluate, u, p, tangent=False, pressures=q)
            fac = clock(f"factorisation {tag}", linear[tag].factorize, ev.K)
            clock(f"solve (2 rhs) {tag}", fac.solve, np.column_stack((-ev.R, ev.g)))
    for key in ("set-up", "tangent evaluation", "residual evaluation", "factorisation",
                "solve (2 rhs)"):
        before = float(np.median(times[f"{key} before"][1:]))
        after = float(np.median(times[f"{key} after"][1:]))
        print(json.dumps({"unit": key, "before_ms": round(1e3 * before, 1),
                          "after_ms": round(1e3 * after, 1), "ratio": round(after / before, 2)}),
              flush=True)


def curves(tree: pathlib.Path, n: int, threads: int | None) -> None:
    env = dict(os.environ)
    if threads is not None:
        for name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            env[name] = str(threads)
    files = {tag: tree.parent / f"{tag}.npz" for tag in ("before", "after")}
    for _ in range(n):
        for tag, path in (("before", tree), ("after", ROOT)):
            out = subprocess.run([sys.executable, "-c", CURVE], check=True, text=True,
                                 capture_output=True, cwd=tempfile.gettempdir(),
                                 env={**env, "PYTHONPATH": str(path),
                                      "CURVE_FILE": str(files[tag])})
            print(json.dumps({"curve": tag, **json.loads(out.stdout)}), flush=True)
    if n:
        print(json.dumps(agreement(*(dict(np.load(files[t])) for t in ("before", "after")))))


def agreement(before: dict, after: dict) -> dict:
    """Whether the two curves have the same points (injected volumes to 1e-12), and the
    largest relative difference of pressure and angle over the points after the first."""
    same = (len(before["volume_ul"]) == len(after["volume_ul"])
            and np.allclose(before["volume_ul"], after["volume_ul"], rtol=1e-12, atol=0.0))
    out = {"same_volumes": bool(same), "points": len(after["volume_ul"])}
    if same:
        for key in ("pressure_pa", "angle_deg"):
            b, a = before[key][1:], after[key][1:]
            out[f"max_rel_diff_{key}"] = float(np.max(np.abs(a - b) / np.abs(b)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rev", help="the git revision to compare the working tree against")
    ap.add_argument("--curves", type=int, default=0, help="full curves per version")
    ap.add_argument("--threads", type=int, default=None,
                    help="OMP_NUM_THREADS and MKL_NUM_THREADS for the curves (wall-clock runs)")
    ap.add_argument("--no-units", action="store_true", help="skip the unit costs")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tree = export(args.rev, pathlib.Path(tmp))
        if not args.no_units:
            unit_costs(pathlib.Path(tmp) / "renamed")
        curves(tree, args.curves, args.threads)


if __name__ == "__main__":
    main()
