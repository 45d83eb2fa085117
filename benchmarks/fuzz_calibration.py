"""Odd but valid lab data through the calibration loop, for a while: any answer other than
a report or a one-line InputError is a bug.

    python benchmarks/fuzz_calibration.py --seed 1 --seconds 900

Each run takes one of the unseen lab sets (tests/test_calibration_unseen.py: FE records
of the shipped database read the way labs read them) and mutates it one way: every
pressure 0, a constant angle, one or two readings per curve, identical replicates, 30 deg
of noise, pressures shifted below 0, time running backwards, shuffled rows, a flow rate of
0, half the rows dropped, every angle negative, pressures x 1000, one time for every
reading, the curves read as runs of a few specimens (or all of one), a column renamed to
a header with a unit (`Pressure (kPa)`, `Angle [rad]`, `t [min]` ...) or given twice.
Printed: BUG (an exception other than InputError), MULTILINE (an InputError of
more than one line), AFTER>BEFORE (a report whose rmse_after exceeds rmse_before), SLOW
(over 60 s), and the count.
"""

from __future__ import annotations

import argparse
import copy
import sys
import time
import traceback
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import test_calibration_unseen as unseen  # noqa: E402

from solver.errors import InputError  # noqa: E402
from surrogate.calibration import run_calibration  # noqa: E402


def _first_readings(rows: list[dict], n: int) -> list[dict]:
    count: dict[str, int] = {}
    out = []
    for r in rows:
        count[r["curve_id"]] = count.get(r["curve_id"], 0) + 1
        if count[r["curve_id"]] <= n:
            out.append(r)
    return out


def _identical_replicates(rows: list[dict]) -> list[dict]:
    ids = sorted({r["curve_id"] for r in rows})
    ref = [r for r in rows if r["curve_id"] == ids[0]]
    return [{**r, "curve_id": i} for i in ids for r in ref]


def _each(column: str, f):
    def apply(rows: list[dict]) -> list[dict]:
        return [{**r, column: f(r[column])} if column in r else r for r in rows]
    return apply


def _as_runs(per_specimen: int):
    """The curves read as runs: every ``per_specimen`` curves one specimen (the run column,
    docs/measured-data.md "Runs"); one specimen holding every curve is refused."""
    def apply(rows: list[dict]) -> list[dict]:
        ids = sorted({r["curve_id"] for r in rows})
        where = {c: (f"spec{i // per_specimen}", i % per_specimen) for i, c in enumerate(ids)}
        return [{**r, "curve_id": where[r["curve_id"]][0], "run": where[r["curve_id"]][1]}
                for r in rows]
    return apply


def _header(column: str, header: str, per_unit: float):
    """``column`` renamed to a header with a unit, its values divided by ``per_unit`` (the
    unit's size in the column's own unit): ``Pressure (kPa)`` holds pressure_pa / 1000."""
    def apply(rows: list[dict]) -> list[dict]:
        out = []
        for r in rows:
            r = dict(r)
            if column in r:
                value = r.pop(column)
                r[header] = value / per_unit if isinstance(value, (int, float)) else value
            out.append(r)
        return out
    return apply


def mutations(rng: np.random.Generator) -> list:
    return [
        _each("pressure_pa", lambda p: 0.0),
        _each("angle_deg", lambda a: 5.0),
        lambda rows: _first_readings(rows, 1),
        lambda rows: _first_readings(rows, 2),
        _identical_replicates,
        _each("angle_deg", lambda a: a + rng.normal(0.0, 30.0)),
        _each("pressure_pa", lambda p: p - 200.0),
        _each("time_s", lambda t: -t),
        lambda rows: [rows[i] for i in rng.permutation(len(rows))],
        _each("flow_ul_s", lambda q: 0.0),
        lambda rows: [r for r in rows if rng.random() < 0.5],
        _each("angle_deg", lambda a: -abs(a)),
        _each("pressure_pa", lambda p: 1000.0 * p),
        _each("time_s", lambda t: 1.0),
        _as_runs(2),
        _as_runs(3),
        _as_runs(1000),
        _header("pressure_pa", "Pressure (kPa)", 1000.0),
        _header("pressure_pa", "p / psi", 6894.757293168361),
        _header("angle_deg", "Angle [rad]", 180.0 / np.pi),
        _header("time_s", "t [min]", 60.0),
        _header("flow_ul_s", "Flow (ml/min)", 1000.0 / 60.0),
        lambda rows: [{**r, "Pressure (kPa)": r.get("pressure_pa", 0.0) / 1000.0} for r in rows],
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--seconds", type=float, default=600.0)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    emulator = unseen._emulator()
    bases = [c for c in unseen.CASES if c.expect.kind != "error"]
    todo = mutations(rng)
    runs = bugs = 0
    end = time.time() + args.seconds
    while time.time() < end:
        case = bases[rng.integers(len(bases))]
        k = int(rng.integers(len(todo)))
        rows = todo[k](copy.deepcopy(case.rows()))
        runs += 1
        t0 = time.time()
        try:
            report = run_calibration(rows, emulator).report
            if report["rmse_after_deg"] > report["rmse_before_deg"] + 1e-9:
                print("AFTER>BEFORE", case.id, k, flush=True)
        except InputError as exc:
            if "\n" in str(exc):
                print("MULTILINE", case.id, k, str(exc)[:200], flush=True)
        except Exception as exc:  # noqa: BLE001 -- the bug this script looks for
            bugs += 1
            print("BUG", case.id, k, type(exc).__name__, str(exc)[:200], flush=True)
            traceback.print_exc(limit=4)
        if time.time() - t0 > 60:
            print("SLOW", case.id, k, round(time.time() - t0), flush=True)
    print(f"runs {runs}, bugs {bugs}")
    return 1 if bugs else 0


if __name__ == "__main__":
    raise SystemExit(main())
