"""Benchmark: the solver at a git revision against the working tree, in CPU time.

For speed-only changes on a loaded machine: wall times there mean little, so both versions
are timed by the CPU time of their process (one thread), and compared in one run.

    OMP_NUM_THREADS=1 python benchmarks/compare_solver_revisions.py REV [--curves N]

- unit costs, alternating in one process at the 30-degree state of the standard design
  (the revision's ``solver/`` exported with ``git archive`` and imported as ``solver_base``):
  model set-up, tangent and residual-only evaluation, PARDISO factorisation and solve;
- ``--curves N``: N full standard curves per version, alternating, one process each
  (``solve(Design(), SolverSettings())``): CPU time, counts, p at 30 / 60 deg, peak RSS.

Results are recorded in benchmarks/RESULTS.md (issue 12, third session).
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
import json, resource, time
import numpy as np
from solver import Design, SolverSettings
from solver.stepping import solve
t0 = time.process_time()
c = solve(Design(), SolverSettings())
t = c.timings_s
print(json.dumps({"cpu_s": round(time.process_time() - t0, 2), "steps": len(c) - 1,
    "solves": int(c.newton_iterations.sum()), "tangents": t.get("tangent_evaluations"),
    "residuals": t.get("residual_evaluations"), "factorisations": t.get("factorisations"),
    "cutbacks": t.get("cutbacks", 0),
    "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
    "p_at_30_60_deg_pa": [float(np.interp(a, c.angle_deg, c.pressure_pa)) for a in (30, 60)]}))
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
    import solver_base.model as base_model
    from solver_base import Design as BaseDesign
    from solver_base import SolverSettings as BaseSettings

    import solver.linear as new_linear
    import solver.model as new_model
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


def curves(tree: pathlib.Path, n: int) -> None:
    for _ in range(n):
        for tag, path in (("before", tree), ("after", ROOT)):
            out = subprocess.run([sys.executable, "-c", CURVE], check=True, text=True,
                                 capture_output=True, cwd=tempfile.gettempdir(),
                                 env={**os.environ, "PYTHONPATH": str(path)})
            print(json.dumps({"curve": tag, **json.loads(out.stdout)}), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rev", help="the git revision to compare the working tree against")
    ap.add_argument("--curves", type=int, default=0, help="full curves per version")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tree = export(args.rev, pathlib.Path(tmp))
        unit_costs(pathlib.Path(tmp) / "renamed")
        curves(tree, args.curves)


if __name__ == "__main__":
    main()
