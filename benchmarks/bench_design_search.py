"""Inverse design over the whole box with the emulator: wall and CPU time per search.

    python benchmarks/bench_design_search.py [--emulator service/data/emulator.json]
    python benchmarks/bench_design_search.py --compare <git revision>
    python benchmarks/bench_design_search.py --pump


Three searches of the shipped emulator over the default box (all four pairs, 512 Sobol
candidates each, then the chamber length solved for the best): an angle target that many
designs meet, an angle no design reaches and a force target no design reaches (the
explorer's and the README client's cases). ``--compare`` runs the same searches with the
code of another revision (a temporary git worktree) in alternating subprocesses, so both
see the same machine load; the figure to read is the ratio. ``--pump`` times a syringe
pump's targets (45 deg at 20 ul, within 20 ul, after 8 s at 2.5 ul/s) against 45 deg at
1500 Pa in the same process, alternately for ``--rounds`` rounds: the ratio of each to the
search by pressure.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGETS = [("angle_at_pressure", 1500.0, {"angle_deg": 30.0}),
           ("angle_at_pressure", 200.0, {"angle_deg": 300.0}),
           ("force_at_pressure", 1500.0, {"force_mn": 10.0})]
PUMP_TARGETS = [("angle_at_pressure", 1500.0, {"angle_deg": 45.0}),
                ("angle_at_volume", None, {"volume_ul": 20.0, "angle_deg": 45.0}),
                ("volume_budget", None, {"volume_ul": 20.0, "angle_deg": 45.0}),
                ("angle_at_time", None, {"time_s": 8.0, "flow_ul_s": 2.5, "angle_deg": 45.0})]

CHILD = """
import json, sys, time
from surrogate.emulator import load_emulator
from surrogate.search.design_search import SearchBounds, search_designs
from surrogate.search.design_target import DesignTarget
e = load_emulator(sys.argv[1])
out = []
for kind, p, kw in json.loads(sys.argv[2]):
    t = DesignTarget(kind, p, **kw)
    w0, c0 = time.perf_counter(), time.process_time()
    r = search_designs(e, t, SearchBounds())
    where = "" if p is None else f" {p:g} Pa"
    out.append({"target": f"{kind}{where} {kw}", "wall_s": time.perf_counter() - w0,
                "cpu_s": time.process_time() - c0, "feasible": r.feasible,
                "n_evaluated": r.n_evaluated,
                "ranked": [[c.family] + [round(getattr(c.design, n), 3) for n in
                            ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm")] for c in r.candidates]})
print(json.dumps(out))
"""


def run(code_root: Path, emulator: str, targets: list = TARGETS) -> list[dict]:
    env = {**os.environ, "PYTHONPATH": str(code_root), "OMP_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", CHILD, emulator, json.dumps(targets)],
                         env=env, capture_output=True, text=True, check=True, cwd=code_root)
    return json.loads(out.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--emulator", default=str(ROOT / "service/data/emulator.json"))
    ap.add_argument("--compare", help="a git revision to time against this checkout")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--pump", action="store_true", help="a pump's targets against one by "
                    "pressure, in one process")
    args = ap.parse_args()
    emulator = str(Path(args.emulator).resolve())
    if args.pump:
        for k in range(args.rounds):
            rows = run(ROOT, emulator, PUMP_TARGETS)
            for row in rows:
                print(f"round {k + 1} {row['target']}: {row['cpu_s']:.2f} s CPU, "
                      f"{row['wall_s']:.2f} s wall (ratio to the first "
                      f"{row['cpu_s'] / rows[0]['cpu_s']:.2f}), {row['n_evaluated']} "
                      f"designs evaluated, feasible {row['feasible']}")
        return
    if not args.compare:
        for row in run(ROOT, emulator):
            print(f"{row['target']}: {row['wall_s']:.2f} s wall, {row['cpu_s']:.2f} s CPU, "
                  f"{row['n_evaluated']} designs evaluated, feasible {row['feasible']}")
        return
    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp) / "old"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(old),
                        args.compare], check=True, capture_output=True)
        try:
            for k in range(args.rounds):
                before, after = run(old, emulator), run(ROOT, emulator)
                for b, a in zip(before, after, strict=True):
                    print(f"round {k + 1} {a['target']}: CPU {b['cpu_s']:.2f} -> "
                          f"{a['cpu_s']:.2f} s (ratio {a['cpu_s'] / b['cpu_s']:.2f}), wall "
                          f"{b['wall_s']:.2f} -> {a['wall_s']:.2f} s; designs evaluated "
                          f"{b['n_evaluated']} -> {a['n_evaluated']}; the same ranked designs "
                          f"(to 1e-3 mm): {b['ranked'] == a['ranked']}")
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                            str(old)], check=False, capture_output=True)


if __name__ == "__main__":
    main()
