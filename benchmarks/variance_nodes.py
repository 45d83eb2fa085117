"""Which pressure nodes a query computes the variance at (emulator.VARIANCE_NODES).

A query's costly part is the exact GP variance, one O(n^2) triangular product per node;
the other nodes' variance is read off the natural cubic spline of log variance in log
angle (emulator.spread_variance). Each node's GP has its own hyperparameters, so which
nodes the spline needs depends on the fit. This script draws random designs of the box
per group, removes nodes greedily (always the one whose removal raises the largest +
2 x the median relative sd error least; the first and last nodes stay) down to --count,
and reports the set with its errors on designs drawn with other seeds.

    python benchmarks/variance_nodes.py [--emulator service/data/emulator.json] [--count 17]
"""

from __future__ import annotations

import argparse

import numpy as np

from surrogate.emulator import load_emulator
from surrogate.emulator.emulator import _VARIANCE_FLOOR, N_NODES, VARIANCE_NODES, spline_matrix
from surrogate.emulator.features import ANGLE_NODES_DEG


def exact_variances(emulator, seed: int, per_group: int) -> np.ndarray:
    """(designs, N_NODES) exact variance of log p at random unit coordinates per group."""
    rng = np.random.default_rng(seed)
    out = []
    for pe in emulator.pairs.values():
        for _ in range(per_group):
            u = rng.uniform(0, 1, pe.coordinates.shape[1])
            out.append(pe.curves.predict(u)[1][:N_NODES])
    return np.array(out)


def errors(nodes, exact: np.ndarray) -> tuple[float, float]:
    """Largest and median (over designs) of the largest relative sd error per design."""
    nodes = np.asarray(nodes)
    b = spline_matrix(ANGLE_NODES_DEG[nodes], ANGLE_NODES_DEG)
    read = np.exp(np.log(np.maximum(exact[:, nodes], _VARIANCE_FLOOR)) @ b.T)
    worst = np.abs(np.sqrt(read / exact) - 1).max(axis=1)
    return float(worst.max()), float(np.median(worst))


def greedy(exact: np.ndarray, count: int) -> list[int]:
    nodes = list(range(N_NODES))
    while len(nodes) > count:
        def cost(n):
            big, med = errors([m for m in nodes if m != n], exact)
            return big + 2 * med
        nodes.remove(min(nodes[1:-1], key=cost))
    return nodes


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--count", type=int, default=len(VARIANCE_NODES))
    ap.add_argument("--per-group", type=int, default=25)
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    fit = np.vstack([exact_variances(e, s, args.per_group) for s in (7, 99)])
    check = exact_variances(e, 123, args.per_group)
    chosen = greedy(fit, args.count)
    for name, nodes in (("shipped VARIANCE_NODES", VARIANCE_NODES.tolist()),
                        (f"greedy {args.count}", chosen)):
        big, med = errors(nodes, check)
        print(f"{name}: {nodes}\n  on {len(check)} other designs: largest {100 * big:.1f} %, "
              f"median {100 * med:.1f} % of the exact sd")


if __name__ == "__main__":
    main()
