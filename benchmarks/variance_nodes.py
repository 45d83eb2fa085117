"""The variance nodes of an emulator file (surrogate/emulator/variance_nodes.py): the
file's set and a greedy choice of --count nodes, with their errors on random designs of
the box not used to choose them. A fit chooses its own since emulator file format 8.

    python benchmarks/variance_nodes.py [--emulator service/data/emulator.json] [--count 17]
"""

from __future__ import annotations

import argparse

import numpy as np

from surrogate.emulator import load_emulator
from surrogate.emulator.variance_nodes import COUNT, SEEDS, errors, exact_variances, greedy


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--count", type=int, default=COUNT)
    ap.add_argument("--per-group", type=int, default=25)
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    pairs = [pe for pe in e.pairs.values() if pe.curves.per_output]
    fit = np.vstack([exact_variances(pairs, s, args.per_group) for s in SEEDS])
    check = exact_variances(pairs, 123, args.per_group)
    for name, nodes in (("the file's variance_nodes", e.variance_nodes.tolist()),
                        (f"greedy {args.count}", greedy(fit, args.count).tolist())):
        big, med = errors(nodes, check)
        print(f"{name}: {nodes}\n  on {len(check)} other designs: largest {100 * big:.1f} %, "
              f"median {100 * med:.1f} % of the exact sd")


if __name__ == "__main__":
    main()
