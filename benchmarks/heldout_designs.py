"""Held-out FE curves for the emulator's accuracy: random designs inside the box.

    python benchmarks/heldout_designs.py --n 12 --seed 2026 --db heldout.h5 --workers 2
    python benchmarks/heldout_designs.py --n 12 --seed 2026 --db heldout.h5 --blocked 4
    python benchmarks/heldout_designs.py --n 48 --seed 3040 --db cal.h5 --blocked-only

Draws designs uniformly (linear in every length and in each layer's stiffness scale, the
pairs in turn) with numpy's generator -- not the database's Sobol sequence -- and solves
them with the default FE through the precompute job (resumable); ``--blocked K`` also
solves the first K of them with the tip held (the database's force variant, to
BLOCKED_MAX_PRESSURE_PA); ``--blocked-only`` solves every design with the tip held and
none free (the force band's calibration set). The emulator is then
compared with them by benchmarks/bench_emulator.py.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np

from solver.design import Design
from solver.design_space import BOX_MM, PAIRS, STIFFNESS_SCALE_RANGE, scaled_material
from solver.precompute.grid import BLOCKED_MAX_PRESSURE_PA, Grid, GridPoint
from solver.settings import SolverSettings
from solver.store.keys import record_key


def random_designs(n: int, seed: int) -> list[Design]:
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        body, membrane = PAIRS[i % len(PAIRS)]
        geometry = {k: round(float(rng.uniform(*r)), 4) for k, r in BOX_MM.items()}
        s_body, s_membrane = (round(float(rng.uniform(*STIFFNESS_SCALE_RANGE)), 4)
                              for _ in range(2))
        out.append(Design(body_material=scaled_material(body, s_body),
                          membrane_material=scaled_material(membrane, s_membrane),
                          **geometry).validated())
    return out


def main() -> None:
    from solver.precompute import precompute

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=12)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--db", default="heldout.h5")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--blocked", type=int, default=0, metavar="K",
                    help="also solve the first K designs with the tip held (force)")
    ap.add_argument("--blocked-only", action="store_true",
                    help="solve every design with the tip held, none free")
    args = ap.parse_args()
    settings = SolverSettings()
    blocked = replace(settings, tip="blocked", max_pressure_pa=BLOCKED_MAX_PRESSURE_PA)
    designs = random_designs(args.n, args.seed)
    free = () if args.blocked_only else designs
    held = designs if args.blocked_only else designs[:args.blocked]
    points = tuple(GridPoint(record_key(d, settings), d, settings) for d in free)
    points += tuple(GridPoint(record_key(d, blocked), d, blocked) for d in held)
    grid = Grid("heldout", f"heldout n={args.n} seed={args.seed}", settings, points)
    summary = precompute(grid, args.db, workers=args.workers, progress=False,
                         command=f"python benchmarks/heldout_designs.py --n {args.n} "
                                 f"--seed {args.seed} "
                                 + ("--blocked-only" if args.blocked_only
                                    else f"--blocked {args.blocked}"))
    print("\n".join(summary.lines()))


if __name__ == "__main__":
    main()
