"""The emulator's held-out accuracy against database size: when to stop adding FE curves.

    python benchmarks/emulator_vs_size.py --db service/data/curves.h5 --heldout heldout.h5 \\
        --fractions 0.25 0.5 0.75 1

For each fraction f, the emulator is fitted to the first f of the database's free-tip
curves (in the order they were solved: the Sobol sequence's prefixes, then the adaptive
rounds; blocked-tip and failed records are all kept) and compared with the held-out FE
curves of benchmarks/heldout_designs.py, as in benchmarks/bench_emulator.py.
"""

from __future__ import annotations

import argparse
import time

from bench_emulator import evaluate

from solver.store import CurveStore
from surrogate.emulator.build import fit_emulator


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--db", default="service/data/curves.h5")
    ap.add_argument("--heldout", required=True)
    ap.add_argument("--fractions", type=float, nargs="+", default=[0.25, 0.5, 0.75, 1.0])
    args = ap.parse_args()
    with CurveStore(args.db) as db:
        records = list(db.records(status=None))
    with CurveStore(args.heldout) as db:
        heldout = [r for r in db.records() if r.status == "complete"]
    records.sort(key=lambda r: r.provenance.get("created_utc", ""))
    free = [r for r in records if r.settings.tip == "free" and r.status == "complete"]
    others = [r for r in records if not (r.settings.tip == "free" and r.status == "complete")]
    print(f"{'free-tip curves':>15s} {'fit s':>6s}  held-out")
    for f in args.fractions:
        subset = free[:max(1, round(f * len(free)))]
        t0 = time.perf_counter()
        e = fit_emulator(subset + others)
        fit_s = time.perf_counter() - t0
        groups = ", ".join(f"{k} {v['designs']}" for k, v in e.report["pairs"].items()
                           if v.get("fitted"))
        print(f"{len(subset):15d} {fit_s:6.1f}  {evaluate(e, heldout).summary()}\n"
              f"{'':23s}groups: {groups}")


if __name__ == "__main__":
    main()
