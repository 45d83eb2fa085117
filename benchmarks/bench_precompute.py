"""Precompute throughput and database put cost.

    .venv/bin/python benchmarks/bench_precompute.py jobs [--mesh reference|tiny] [--designs 4]
    .venv/bin/python benchmarks/bench_precompute.py puts [--sizes 10 100 1000 3000]

jobs: designs per hour of ``precompute`` with 1 and with 2 worker processes on a fixed
      grid (PDMS 1:10 / Ecoflex 00-30, t = 0.5 mm, L from 4.1 mm in 1 mm steps), each run
      into a fresh database; the speed-up of 2 workers over 1. "reference" is
      SolverSettings() (the default mesh); "tiny" is mesh_level=0, hex1, 10 deg.
puts: seconds per put (one record of 60 steps) against the number of records already in
      the file: the copy-on-write publish copies the whole file, so this grows linearly.
Results go to benchmarks/RESULTS.md by hand (command, machine, figures).
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

MESHES = {"reference": {}, "tiny": {"mesh_level": 0, "element": "hex1", "max_angle_deg": 10}}


def grid_text(designs: int, mesh: str) -> str:
    lengths = ", ".join(f"{4.1 + i:.1f}" for i in range(designs))
    settings = "".join(f"{k} = {v!r}\n".replace("'", '"') for k, v in MESHES[mesh].items())
    return (f'pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = [{lengths}]\nt_mm = 0.5\n'
            f"[settings]\n{settings}")


def bench_jobs(args: argparse.Namespace) -> None:
    from solver.precompute import parse_grid, precompute

    grid = parse_grid(grid_text(args.designs, args.mesh), "bench")
    rates = {}
    for workers in args.workers:
        with tempfile.TemporaryDirectory() as tmp:
            summary = precompute(grid, Path(tmp) / "bench.h5", workers=workers,
                                 progress=False)
        rates[workers] = summary.designs_per_hour
        print(f"{workers} worker(s): {summary.solved} designs ({summary.complete} complete, "
              f"{summary.failed} failed) in {summary.wall_time_s:.1f} s = "
              f"{summary.designs_per_hour:.0f} designs/h", flush=True)
    if 1 in rates and 2 in rates:
        print(f"speed-up 2 workers / 1 worker: {rates[2] / rates[1]:.2f}x")


def bench_puts(args: argparse.Namespace) -> None:
    import numpy as np

    from solver.curve import Curve
    from solver.design import Design
    from solver.settings import SolverSettings
    from solver.store import CurveStore, make_record

    def record(i: int):
        n = 60
        p = np.linspace(0.0, 2000.0, n)
        curve = Curve(pressure_pa=p, volume_ul=p / 100, time_s=p / 250, angle_deg=p / 20,
                      tip_displacement_mm=np.c_[p, p] / 1e3, max_membrane_stretch=1 + p / 1e4,
                      force_mn=np.full(n, np.nan), newton_iterations=np.full(n, 5),
                      residual_norm=np.full(n, 1e-10), negative_eigenvalues=np.zeros(n, int),
                      status="complete", reason="bench", n_dofs=5000, wall_time_s=30.0,
                      timings_s={"assembly": 10.0, "linear": 15.0})
        return make_record(Design(L_mm=4.0 + 1e-4 * i), SolverSettings(), curve)

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "curves.h5"
        with CurveStore(path, mode="a") as db:
            count = 0
            for size in args.sizes:
                while count < size:  # fill in batches: one copy per batch
                    batch = min(500, size - count)
                    db.put_many([record(count + j) for j in range(batch)])
                    count += batch
                times = []
                for _ in range(5):
                    start = time.perf_counter()
                    db.put(record(count))
                    times.append(time.perf_counter() - start)
                    count += 1
                mb = os.path.getsize(path) / 1e6
                print(f"{count:6d} records, {mb:7.1f} MB: put {1e3 * np.median(times):7.1f} ms "
                      f"(median of 5), {1e3 * mb / count:.1f} kB per record", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(required=True)
    jobs = sub.add_parser("jobs")
    jobs.add_argument("--mesh", choices=tuple(MESHES), default="reference")
    jobs.add_argument("--designs", type=int, default=4)
    jobs.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    jobs.set_defaults(func=bench_jobs)
    puts = sub.add_parser("puts")
    puts.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000, 3000])
    puts.set_defaults(func=bench_puts)
    args = parser.parse_args()
    print(f"machine: {platform.node()} {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}", flush=True)
    args.func(args)


if __name__ == "__main__":
    main()
