"""The database designs whose FE curve ended early, asked at their own FE points.

    python benchmarks/early_ended_database_designs.py [--emulator service/data/emulator.json]
        [--db service/data/curves.h5]

Every default-FE free-tip record of the database that ended before 90 deg (the volume
stop, a Newton failure, the pressure stop) and lies in the emulator's box, asked by
pressure (``Emulator.predict``) and by injected volume (``Emulator.predict_volume``) at
every FE point of its own curve: how many are within the issue's 0.2 deg (RMS over the
answered points; a design refused, or with no answered point, counts as a miss), and the
share of the FE points answered. About a minute on one core.
``tests/test_emulator.py::test_early_ended_database_designs_are_reproduced`` asks every
third of them.
"""

from __future__ import annotations

import argparse

import numpy as np

from solver.design_space import locate
from solver.errors import InputError
from solver.settings import SolverSettings
from solver.store import CurveStore
from surrogate.emulator import load_emulator

TARGET_DEG = 0.2
LIMIT_ANGLE_DEG = 90.0


def early_ended_records(db_path: str) -> list:
    """The database's default-FE free-tip records that ended before LIMIT_ANGLE_DEG and
    lie in the reduced box."""
    out = []
    with CurveStore(db_path) as db:
        for rec in db.records():
            c = rec.curve
            if (rec.settings != SolverSettings() or c is None or len(c.angle_deg) < 3
                    or np.abs(c.angle_deg).max() >= LIMIT_ANGLE_DEG):
                continue
            try:
                locate(rec.design, reduced=True)
            except InputError:
                continue
            out.append(rec)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--db", default="service/data/curves.h5")
    args = ap.parse_args()
    emulator = load_emulator(args.emulator)
    records = early_ended_records(args.db)
    for axis in ("pressure", "volume"):
        ask = emulator.predict if axis == "pressure" else emulator.predict_volume
        within, answered = 0, []
        for rec in records:
            c = rec.curve
            x = c.pressure_pa if axis == "pressure" else c.volume_ul
            keep = x > 0
            try:
                angle = np.asarray(ask(rec.design, x[keep]).angle_deg, float)
            except InputError:
                answered.append(0.0)
                continue
            ok = np.isfinite(angle)
            answered.append(float(ok.mean()))
            error = angle[ok] - c.angle_deg[keep][ok]
            if ok.any() and np.sqrt(np.mean(error ** 2)) <= TARGET_DEG:
                within += 1
        print(f"by {axis}: {within} of {len(records)} early-ended database designs within "
              f"{TARGET_DEG:g} deg RMS; answered share of their FE points "
              f"{np.mean(answered):.3f}")


if __name__ == "__main__":
    main()
