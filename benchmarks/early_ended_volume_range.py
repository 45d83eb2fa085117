"""Early-ended FE curves: how far past their FE end the emulator answers, and at what cost.

    python benchmarks/early_ended_volume_range.py [--emulator service/data/emulator.json]
        [--sets <sets>] [--database service/data/curves.h5]
        [--end-volumes-from service/data/curves.h5]

Every default-FE free-tip curve of the sets (default: the ten of designs drawn uniformly
from the box, none in the database, ``TEN_SETS``; ``emulator_random_curves.py``) is asked
by chamber pressure (``Emulator.predict``) and by injected volume
(``Emulator.predict_volume``) at its own FE points up to 90 deg, and each curve whose FE
ended before 90 deg (a Newton failure, the 500 ul volume stop) also at PAST_PRESSURE x its
last FE pressure and PAST_VOLUME x its last FE injected volume, where the FE gives no
angle, so neither should the emulator. Prints, per axis: (a) how many early-ended curves
are answered at each factor, (b) the complete and early-ended curves within the
per-curve target (RMSE <= 1 deg and max <= 3 deg over the answered points; a curve with
none answered counts as a miss, so one more complete curve than ``emulator_random_curves``
counts), (c) the answered share of the FE points. A design refused (the stiffness
balance) is counted as refused. ``--database`` does the same for the database's own
early-ended designs (``early_ended_database_designs.early_ended_records``). About 15 s
for the ten sets and 25 s for the database's 558 on one core.

``--end-volumes-from DB`` attaches to an emulator file of format 14 the early-ended
database curves' last FE volumes as a refit on DB stores them (``failed_end_volume_ul``),
to measure the range they cap without a refit. Figures: benchmarks/RESULTS.md (thirty-ninth
session).
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np
from early_ended_database_designs import early_ended_records
from emulator_random_curves import LIMIT_ANGLE_DEG, TARGET_MAX_DEG, TARGET_RMSE_DEG

from solver.errors import InputError
from solver.settings import SolverSettings
from solver.store import CurveStore
from surrogate.emulator import load_emulator

TEN_SETS = ("service/data/band-calibration.h5",) + tuple(
    f"benchmarks/heldout/ho{seed}.h5" for seed in (*range(2028, 2036), 4242))
PAST_PRESSURE = (1.01, 1.02, 1.05, 1.1)
PAST_VOLUME = (1.05, 1.1, 1.2, 1.5)


def with_end_volumes(emulator, db_path: str):
    """``emulator`` with each pair's ``failed_end_volume_ul`` as a refit on the database
    at ``db_path`` would store it (``database_rows.collect_rows``; for measurement only, the shipped
    path is the fit); ValueError when an early-ended curve of the file is not in it."""
    from surrogate.emulator.database_rows import collect_rows

    with CurveStore(db_path) as db:
        free, _, _ = collect_rows(db.records())
    pairs = {}
    for key, pe in emulator.pairs.items():
        rows = free[key[:-1]]
        found = np.array([f[0] for f in rows.failed], float)
        volumes = []
        for u, _, _ in pe.failed:
            d = np.abs(found - u).max(axis=1)
            if d.min() > 1e-9:
                raise ValueError(f"{key}: an early-ended curve of the file is not in {db_path}")
            volumes.append(rows.failed_end_volume[int(np.argmin(d))])
        pairs[key] = replace(pe, failed_end_volume_ul=np.array(volumes, float))
    return replace(emulator, pairs=pairs)


def default_free_records(paths: tuple[str, ...]) -> list:
    """The default-FE free-tip records of the sets at ``paths`` with three points or more."""
    out = []
    for path in paths:
        with CurveStore(path) as db:
            out += [rec for rec in db.records() if rec.settings == SolverSettings()
                    and rec.curve is not None and len(rec.curve.pressure_pa) >= 3]
    return out


def measure(emulator, records: list) -> dict:
    """Per axis: per-curve (complete, RMSE, max, answered FE points, FE points) and, for
    the early-ended curves, whether each factor past the end was answered."""
    out: dict = {"pressure": [], "volume": [], "past_pressure": [], "past_volume": [],
                 "refused": 0}
    for rec in records:
        c = rec.curve
        complete = bool(abs(c.angle_deg[-1]) >= LIMIT_ANGLE_DEG - 1e-6)
        try:
            for axis, x, ask, factors in (
                    ("pressure", c.pressure_pa, emulator.predict, PAST_PRESSURE),
                    ("volume", c.volume_ul, emulator.predict_volume, PAST_VOLUME)):
                keep = (x > 0) & (np.abs(c.angle_deg) <= LIMIT_ANGLE_DEG)
                angle = np.asarray(ask(rec.design, x[keep]).angle_deg, float)
                err = (angle - c.angle_deg[keep])[np.isfinite(angle)]
                rmse = float(np.sqrt(np.mean(err**2))) if err.size else np.inf
                worst = float(np.abs(err).max()) if err.size else np.inf
                out[axis].append((complete, rmse, worst, err.size, int(keep.sum())))
                if not complete:
                    past = np.asarray(ask(rec.design, x[-1] * np.array(factors)).angle_deg,
                                      float)
                    out["past_" + axis].append(np.isfinite(past))
        except InputError:
            out["refused"] += 1
    return out


def report(m: dict) -> None:
    for axis, factors in (("pressure", PAST_PRESSURE), ("volume", PAST_VOLUME)):
        rows = np.array(m[axis], float).reshape(-1, 5)
        hit = (rows[:, 1] <= TARGET_RMSE_DEG) & (rows[:, 2] <= TARGET_MAX_DEG)
        past = np.array(m["past_" + axis]).reshape(-1, len(factors))
        print(f"by {axis}: early-ended curves answered at "
              f"{' / '.join(f'{f:g}' for f in factors)}x their last FE {axis}: "
              f"{' / '.join(str(int(n)) for n in past.sum(axis=0))} of {len(past)}")
        for label, sel in (("complete", rows[:, 0] == 1), ("early-ended", rows[:, 0] == 0)):
            if not sel.any():
                continue
            print(f"by {axis}: {label} FE curves: {int(hit[sel].sum())} of {int(sel.sum())} "
                  f"within RMSE <= {TARGET_RMSE_DEG:g} and max <= {TARGET_MAX_DEG:g} deg; "
                  f"answered share of their FE points "
                  f"{rows[sel, 3].sum() / rows[sel, 4].sum():.3f}")
    print(f"refused designs: {m['refused']}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--sets", nargs="+", default=list(TEN_SETS))
    ap.add_argument("--database", metavar="DB", default=None,
                    help="also the early-ended database designs of DB, at their own curves")
    ap.add_argument("--end-volumes-from", metavar="DB", default=None,
                    help="attach the early-ended database curves' end volumes from DB")
    args = ap.parse_args()
    emulator = load_emulator(args.emulator)
    if args.end_volumes_from:
        emulator = with_end_volumes(emulator, args.end_volumes_from)
    print(f"random designs ({len(args.sets)} sets):")
    report(measure(emulator, default_free_records(tuple(args.sets))))
    if args.database:
        print(f"early-ended database designs ({args.database}):")
        report(measure(emulator, early_ended_records(args.database)))


if __name__ == "__main__":
    main()
