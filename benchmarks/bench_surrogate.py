"""Surrogate speed: vectorised prediction (curve points per second, target >= 1e6) and
inverse-design queries (target < 5 ms each).

    .venv/bin/python benchmarks/bench_surrogate.py [--model PATH]

Default model: service/data/surrogate.json when it exists, else a surrogate fitted to
synthetic curves on the paper's simulated grid (8 L x 3 t, two material pairs) -- the
default database's shape. Prints median timings over repeats; results go to
benchmarks/RESULTS.md by hand.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from solver.design import Design
from surrogate import DesignTarget, fit_surrogate, inverse_design, open_surrogate
from surrogate.exponential.paper_tables import SIMULATED_L_MM
from surrogate.exponential.synthetic_curves import synthetic_curves

DEFAULT = Path(__file__).resolve().parents[1] / "service" / "data" / "surrogate.json"


def synthetic_surrogate():
    curves = synthetic_curves(np.array([0.1, 700.0, 7.0, 0.05]), L_mm=SIMULATED_L_MM,
                              noise_deg=0.3, noise_rel=0.02, seed=1)
    curves += synthetic_curves(np.array([-0.05, 900.0, 6.0]), L_mm=SIMULATED_L_MM,
                               body="ecoflex_00_30", membrane="pdms_1_15", noise_deg=0.2,
                               seed=2)
    return fit_surrogate(curves, name="synthetic-benchmark")


def timed(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model", default=None)
    args = parser.parse_args()
    spec = args.model or (str(DEFAULT) if DEFAULT.is_file() else None)
    s = open_surrogate(spec) if spec else synthetic_surrogate()
    print(f"model: {s.name} ({spec or 'synthetic fit'}); {platform.processor() or ''} "
          f"{platform.machine()}, python {platform.python_version()}")
    d = Design()
    p = np.linspace(0.0, 2000.0, 1_000_000)
    s.predict(d, p)
    t = timed(lambda: s.predict(d, p), 7)
    print(f"predict, one design x 1e6 pressures (band + validity): {t * 1e3:.1f} ms "
          f"= {p.size / t / 1e6:.1f} M points/s")
    p1k = np.linspace(0.0, 2000.0, 1000)
    designs = [Design(L_mm=L, t_mm=tt) for L in np.linspace(4.1, 15.1, 25)
               for tt in np.linspace(0.5, 1.0, 40)]
    t = timed(lambda: [s.predict(x, p1k) for x in designs], 3)
    print(f"predict, 1000 designs x 1000 pressures: {t * 1e3:.0f} ms "
          f"= {1e6 / t / 1e6:.1f} M points/s")
    p100 = np.linspace(0.0, 2000.0, 100)
    t = timed(lambda: s.predict(d, p100), 2000)
    print(f"predict, one design x 100 pressures: {t * 1e6:.0f} us per call")
    queries = [(DesignTarget("pressure_budget", 1500.0, angle_deg=30.0), None),
               (DesignTarget("pressure_budget", 1500.0, angle_deg=30.0), "compact"),
               (DesignTarget("pressure_budget", 2000.0, angle_deg=60.0), "margin"),
               (DesignTarget("angle_at_pressure", 1500.0, angle_deg=40.0), None),
               (DesignTarget("angle_at_pressure", 900.0, angle_deg=300.0), None)]
    for target, objective in queries:
        inverse_design(s, target, objective=objective)
        t = timed(lambda target=target, objective=objective: inverse_design(
            s, target, objective=objective), 200)
        res = inverse_design(s, target, objective=objective)
        print(f"inverse_design {target.kind:18s} {res.objective:9s} "
              f"feasible={res.feasible!s:5s} evaluated={res.n_evaluated:5d}: "
              f"{t * 1e3:.2f} ms (median of 200)")


if __name__ == "__main__":
    main()
