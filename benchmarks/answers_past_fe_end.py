"""Answers past the end of random designs' FE curves, and which of them are flagged.

    python benchmarks/answers_past_fe_end.py [--emulator service/data/emulator.json]
        [--sets service/data/band-calibration.h5 benchmarks/heldout/ho2028.h5 ...]

Every default-FE free-tip curve of the sets (random box designs the emulator was not fitted
on) that ended before 90 deg is asked just past its own end: by pressure at 1.01 / 1.02 /
1.05x its largest FE pressure, by injected volume at 1.05 / 1.1 / 1.2 / 1.5x its last FE
volume. An answered angle there is a number past the FE; the line says how many of those
answers carry ``high_membrane_stretch`` (surrogate/emulator/stretch_hazard.py) at such a
point, and how many carry it or another flag that warns of an early end
(``EARLY_END_WARNINGS``). The curves that reached 90 deg are asked at their own
pressures: how many carry the flag, and on how many of their answered points (the flag's
false alarms).
"""

from __future__ import annotations

import argparse

import numpy as np

from solver.errors import InputError
from solver.settings import SolverSettings
from solver.store import CurveStore
from surrogate.emulator import load_emulator
from surrogate.emulator.stretch_hazard import FLAG

TEN_SETS = ("service/data/band-calibration.h5",) + tuple(
    f"benchmarks/heldout/ho{s}.h5" for s in range(2028, 2036)) + (
    "benchmarks/heldout/ho4242.h5",)
PRESSURE_FACTORS = (1.01, 1.02, 1.05)
VOLUME_FACTORS = (1.05, 1.1, 1.2, 1.5)


# the other flags that warn of an early FE end at this design (validity.py, balance.py):
# a database curve nearby ended early; the answer is the stiffness balance's model
EARLY_END_WARNINGS = ("near_early_ended_fe_curves", "near_stiffness_balance")


def warned(answer) -> bool:
    """Whether the answer carries a flag that warns its FE curve may end early or differ
    (``high_membrane_stretch`` at its points is counted by ``flagged_at``)."""
    return any(f in answer.validity["flags"] for f in EARLY_END_WARNINGS)


def flagged_at(answer, at: np.ndarray) -> np.ndarray:
    """Which of the answered points ``at`` (a mask of the answer's points) lie at or past
    the answer's stretch onset (none without the flag)."""
    onset = answer.validity.get("high_stretch_from_deg")
    angle = np.abs(np.asarray(answer.angle_deg, float))
    if FLAG not in answer.validity["flags"] or onset is None:
        return np.zeros(int(at.sum()), bool)
    return angle[at] >= abs(onset) - 1e-9


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--sets", nargs="+", default=list(TEN_SETS))
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    # answered past the end, flagged high_membrane_stretch there, flagged or warned
    by_p = {f: [0, 0, 0] for f in PRESSURE_FACTORS}
    by_v = {f: [0, 0, 0] for f in VOLUME_FACTORS}
    complete = [0, 0, 0, 0]       # curves, flagged curves, answered points, flagged points
    for path in args.sets:
        with CurveStore(path) as db:
            for rec in db.records():
                c = rec.curve
                if (rec.settings != SolverSettings() or c is None
                        or len(c.pressure_pa) < 3):
                    continue
                try:
                    if abs(c.angle_deg[-1]) >= 90.0 - 1e-6:
                        keep = (c.pressure_pa > 0) & (np.abs(c.angle_deg) <= 90.0)
                        a = e.predict(rec.design, c.pressure_pa[keep])
                        ok = np.isfinite(np.asarray(a.angle_deg, float))
                        hit = flagged_at(a, ok)
                        complete = [complete[0] + 1, complete[1] + bool(hit.any()),
                                    complete[2] + int(ok.sum()), complete[3] + int(hit.sum())]
                        continue
                    for factors, counts, ask, end in (
                            (PRESSURE_FACTORS, by_p, e.predict, float(np.max(c.pressure_pa))),
                            (VOLUME_FACTORS, by_v, e.predict_volume,
                             float(np.max(c.volume_ul)))):
                        for f in factors:
                            a = ask(rec.design, [f * end])
                            ok = np.isfinite(np.asarray(a.angle_deg, float))
                            if ok.any():
                                hit = bool(flagged_at(a, ok).any())
                                counts[f][0] += 1
                                counts[f][1] += hit
                                counts[f][2] += hit or warned(a)
                except InputError:
                    continue
    for axis, counts in (("pressure", by_p), ("volume", by_v)):
        print(f"by {axis}, early-ended curves answered past their FE end (flagged "
              f"{FLAG}; that or warned {' or '.join(EARLY_END_WARNINGS)}): "
              + ", ".join(f"{f:g}x {n} ({k}; {w})" for f, (n, k, w) in counts.items()))
    print(f"complete curves carrying {FLAG}: {complete[1]} of {complete[0]}, on "
          f"{complete[3]} of their {complete[2]} answered points")


if __name__ == "__main__":
    main()
