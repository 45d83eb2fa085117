"""Which of the emulator's warning flags fall on the held-out curves it misses?

    python benchmarks/heldout_flags.py [--emulator service/data/emulator.json]
        [--sets benchmarks/heldout/ho*.h5]

Every free-tip FE curve of the sets that ``bench_emulator.scored`` scores is asked at its
own pressures up to 90 deg (``predict``); a curve misses the per-curve target when the
RMSE over its answered points passes 1 deg or their largest error 3 deg. Printed: the
curves by (miss or within, ``high_membrane_stretch`` or not, ``near_early_ended_fe_curves``
or not), and the share of misses among the curves with and without the stretch flag --
what the flag tells a user about the answer's accuracy.
"""

from __future__ import annotations

import argparse
import collections

import numpy as np
from bench_emulator import scored_free_records

from solver.errors import InputError
from surrogate.emulator import load_emulator

FLAGS = ("high_membrane_stretch", "near_early_ended_fe_curves")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--emulator", default="service/data/emulator.json")
    parser.add_argument("--sets", nargs="+", default=None)
    args = parser.parse_args()
    e = load_emulator(args.emulator)
    counts: collections.Counter = collections.Counter()
    for r in scored_free_records(args.sets):
        angle = np.asarray(r.curve.angle_deg)
        pressure = np.asarray(r.curve.pressure_pa)
        keep = (np.abs(angle) <= 90) & (pressure > 0)
        try:
            answer = e.predict(r.design, pressure[keep])
        except InputError:
            counts["refused"] += 1
            continue
        err = np.abs(np.asarray(answer.angle_deg) - angle[keep])
        err = err[np.isfinite(err)]
        if err.size == 0:
            counts["unanswered"] += 1
            continue
        miss = bool(np.sqrt(np.mean(err ** 2)) > 1 or err.max() > 3)
        flags = set(answer.validity.get("flags", []))
        counts[(miss, *(f in flags for f in FLAGS))] += 1
    print(f"{'':>8} {FLAGS[0]:>22} {FLAGS[1]:>27} curves")
    for key in sorted((k for k in counts if isinstance(k, tuple)), key=str):
        print(f"{'miss' if key[0] else 'within':>8} {key[1]!s:>22} {key[2]!s:>27} "
              f"{counts[key]}")
    for flagged in (True, False):
        n = sum(v for k, v in counts.items() if isinstance(k, tuple) and k[1] == flagged)
        misses = sum(v for k, v in counts.items()
                     if isinstance(k, tuple) and k[1] == flagged and k[0])
        print(f"{FLAGS[0]} {'on' if flagged else 'off'}: {misses} of {n} curves miss "
              f"({misses / max(n, 1):.0%})")
    print(f"refused {counts['refused']}, answered at no point {counts['unanswered']}")


if __name__ == "__main__":
    main()
