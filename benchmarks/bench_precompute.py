"""Precompute throughput and database put cost.

    .venv/bin/python benchmarks/bench_precompute.py jobs [--mesh reference|tiny] [--designs 4]
                                                         [--grid balanced|sweep]
    .venv/bin/python benchmarks/bench_precompute.py puts [--sizes 10 100 1000 3000]

jobs: designs per hour of ``precompute`` with 1 and with 2 worker processes, each run into
      a fresh database with a fresh pool, timed from the call to ``precompute`` to its
      return (worker start-up and imports, metadata writes and pool shutdown included);
      the speed-up of 2 workers over 1. Grids (PDMS 1:10 / Ecoflex 00-30, t = 0.5 mm):
      "balanced" (default): L = 7.100, 7.101, ... mm -- the standard design, distinct keys,
      the same mesh and nearly the same solve, so the speed-up measures the job and not
      how unevenly the grid's costs split over 2 workers; "sweep": L = 4.1, 5.1, ... mm
      (a real sweep: L = 4.1 mm costs several times L = 7.1 mm, so with 4 designs the
      2-worker run waits for its slowest design). "reference" is SolverSettings() (the
      default mesh); "tiny" is mesh_level=0, hex1, 10 deg. Exits 1 if a design does not
      complete (a failed solve is fast and would inflate the rate).
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
GRIDS = ("balanced", "sweep")


def grid_text(designs: int, mesh: str, grid: str = "balanced") -> str:
    if grid == "balanced":
        lengths = ", ".join(f"{7.1 + 0.001 * i:.3f}" for i in range(designs))
    else:
        lengths = ", ".join(f"{4.1 + i:.1f}" for i in range(designs))
    settings = "".join(f"{k} = {v!r}\n".replace("'", '"') for k, v in MESHES[mesh].items())
    return (f'pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = [{lengths}]\nt_mm = 0.5\n'
            f"[settings]\n{settings}")


def blas_threads(workers: int) -> str:
    """What PoolBackend gives each worker: the user's OMP_NUM_THREADS, else cores // N."""
    own = os.environ.get("OMP_NUM_THREADS")
    return own + " (OMP_NUM_THREADS)" if own else str(max(1, (os.cpu_count() or 1) // workers))


def bench_jobs(args: argparse.Namespace) -> int:
    from solver.precompute import parse_grid, precompute
    from solver.store import CurveStore

    grid = parse_grid(grid_text(args.designs, args.mesh, args.grid), "bench")
    print(f"grid {args.grid}: {len(grid)} designs, L = "
          f"{', '.join(f'{p.design.L_mm:g}' for p in grid.points)} mm; settings "
          f"{grid.settings}", flush=True)
    rates, ok = {}, True
    for workers in args.workers:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "bench.h5"
            start = time.perf_counter()
            summary = precompute(grid, path, workers=workers, progress=False)
            elapsed = time.perf_counter() - start
            with CurveStore(path) as db:
                solve_s = sorted(float(r["provenance"]["wall_time_s"])
                                 for r in db.summaries()) or [float("nan")]
        rates[workers] = 3600.0 * summary.solved / elapsed
        ok = ok and summary.complete + summary.stopped == len(grid)
        print(f"{workers} worker(s), BLAS threads per worker {blas_threads(workers)}: "
              f"{summary.solved} designs ({summary.complete} complete, {summary.failed} "
              f"failed, {summary.errors} lost) in {elapsed:.1f} s = {rates[workers]:.1f} "
              f"designs/h; per-design solve {solve_s[0]:.1f} .. {solve_s[-1]:.1f} s",
              flush=True)
    if 1 in rates and 2 in rates:
        print(f"speed-up 2 workers / 1 worker: {rates[2] / rates[1]:.2f}x (target >= 1.7x)")
    if not ok:
        print("NOT VALID: some designs did not complete (see above)")
        return 1
    return 0


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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(required=True)
    jobs = sub.add_parser("jobs")
    jobs.add_argument("--mesh", choices=tuple(MESHES), default="reference")
    jobs.add_argument("--designs", type=int, default=4)
    jobs.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    jobs.add_argument("--grid", choices=GRIDS, default="balanced")
    jobs.set_defaults(func=bench_jobs)
    puts = sub.add_parser("puts")
    puts.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000, 3000])
    puts.set_defaults(func=bench_puts)
    args = parser.parse_args()
    print(f"machine: {platform.node()} {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}", flush=True)
    return int(args.func(args) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
