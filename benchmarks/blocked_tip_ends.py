"""The blocked-tip force near and past the end of each design's blocked-tip FE curve.

    python benchmarks/blocked_tip_ends.py [--emulators A.json B.json ...]
        [--db service/data/curves.h5] [--sets benchmarks/heldout/*.h5]

For every blocked-tip FE curve of the database that ended before its pressure stop (a
pressure maximum where Newton fails, the volume stop; these are not in the force model,
which is fitted on the curves that reach the force range) and every blocked-tip curve of
the held-out sets (random designs outside the database), each emulator is asked for the
force at the curve's own pressures and at 1.02 / 1.05 / 1.2 / 1.5 x its last one:

- curves given a force past their FE end;
- the share of the FE points given a force, and of those above 0.8 x the FE end, how many
  the 95 % band covers.

Several emulator files are compared in one run (e.g. the former one from `git show`);
about a minute each on one core.
"""

from __future__ import annotations

import argparse
import glob

import numpy as np

from solver.errors import InputError
from solver.store import CurveStore
from surrogate.emulator import database_rows, load_emulator
from surrogate.emulator.blocked_range import ended_at_pressure_stop

FACTORS = (1.02, 1.05, 1.2, 1.5)
NEAR_END = 0.8


def blocked_curves(db_path: str, sets: list[str]) -> list[tuple[str, object]]:
    """(source, record): the database's early-ended blocked-tip force curves and every
    blocked-tip curve of the held-out sets."""
    out = []
    with CurveStore(db_path) as db:
        out += [("database, ended early", r) for r in db.records()
                if r.curve is not None and database_rows.is_force_record(r.settings)
                and not ended_at_pressure_stop(r.curve.reason)]
    for path in sets:
        with CurveStore(path) as db:
            for r in db.records():
                if r.curve is None or r.settings.tip != "blocked":
                    continue
                kind = "complete" if ended_at_pressure_stop(r.curve.reason) else "ended early"
                out.append((f"held-out, {kind}", r))
    return out


def score(emulator, curves: list) -> dict[str, np.ndarray]:
    """Per source: [curves, curves given a force past the end, FE points, points given a
    force, points above NEAR_END x the end given one, of those inside the band]."""
    out: dict[str, np.ndarray] = {}
    for source, rec in curves:
        c = rec.curve
        end = float(c.pressure_pa[-1])
        ok = np.isfinite(c.force_mn) & (c.pressure_pa > 0)
        p = np.concatenate((c.pressure_pa[ok], end * np.array(FACTORS)))
        try:
            pred = emulator.predict(rec.design, p)
        except InputError:
            continue
        row = out.setdefault(source, np.zeros(6, int))
        row[0] += 1
        if pred.force_mn is None:
            row[2] += int(ok.sum())
            continue
        f = np.asarray(pred.force_mn, float)
        lo, hi = (np.asarray(x, float) for x in (pred.force_lower_mn, pred.force_upper_mn))
        n = int(ok.sum())
        fe = c.force_mn[ok]
        given = np.isfinite(f[:n])
        near = given & (p[:n] > NEAR_END * end)
        row[1] += int(np.isfinite(f[n:]).any())
        row[2] += n
        row[3] += int(given.sum())
        row[4] += int(near.sum())
        row[5] += int(((fe >= lo[:n] - 1e-9) & (fe <= hi[:n] + 1e-9) & near).sum())
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emulators", nargs="+", default=["service/data/emulator.json"])
    ap.add_argument("--db", default="service/data/curves.h5")
    ap.add_argument("--sets", nargs="*", default=sorted(glob.glob("benchmarks/heldout/*.h5")))
    args = ap.parse_args()
    curves = blocked_curves(args.db, args.sets)
    for path in args.emulators:
        print(path)
        for source, r in sorted(score(load_emulator(path), curves).items()):
            # a complete curve stopped at the solve's pressure stop, not at an end
            past = ("" if source.endswith("complete") else
                    f", {r[1]} given a force past their FE end "
                    f"({' / '.join(f'{x:g}' for x in FACTORS)} x)")
            print(f"  {source}: {r[0]} curves{past}; force at {r[3]} of "
                  f"{r[2]} FE points ({r[3] / max(r[2], 1):.3f}); above {NEAR_END:g} x "
                  f"the end at {r[4]}, band covers {r[5] / max(r[4], 1):.3f}")


if __name__ == "__main__":
    main()
