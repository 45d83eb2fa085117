"""An emulator file on every free-tip FE curve of random box designs it did not see.

    python benchmarks/emulator_random_curves.py [--emulator service/data/emulator.json]
        [--sets service/data/band-calibration.h5 benchmarks/heldout/ho2028.h5 ...]

The band calibration set and the held-out sets hold FE curves of designs drawn uniformly
from the box (`benchmarks/heldout_designs.py`), none in the database the emulator was
fitted from; the band calibration set only widened the bands, so the answers themselves
never saw it. Unlike `bench_emulator.py`, the curves of Newton-failed solves count with
their converged part. Each curve is asked at every FE pressure (``Emulator.predict``) and
at every FE injected volume (``Emulator.predict_volume``) up to 90 deg; the answered
points (past the emulated FE range no angle is given) are scored per curve: the issue's
target RMSE <= 1 deg and max <= 3 deg, split by whether the design's own FE curve reached
90 deg or ended early (the FE's volume stop, a Newton failure). A refused design (the
Ecoflex/Ecoflex stiffness balance) is counted as refused. Prints one line per axis and
split; about 2 minutes for the shipped sets on one core.

``--even N`` reads each curve as a lab samples it instead of at the FE's own steps (which
crowd small angles): N points evenly spaced in pressure (or in injected volume, a syringe
pump read at a fixed interval) from end / N to the FE curve's end (its last point up to
90 deg; by pressure, up to a pressure maximum), the FE's angle there interpolated
linearly; a curve with no answered point counts as a miss.
"""

from __future__ import annotations

import argparse

import numpy as np

from solver.errors import InputError
from solver.settings import SolverSettings
from solver.store import CurveStore
from surrogate.emulator import load_emulator

DEFAULT_SETS = ("service/data/band-calibration.h5",) + tuple(
    f"benchmarks/heldout/ho{seed}.h5" for seed in range(2028, 2033))
LIMIT_ANGLE_DEG = 90.0
TARGET_RMSE_DEG, TARGET_MAX_DEG = 1.0, 3.0


def lab_points(x: np.ndarray, angle_deg: np.ndarray, n: int, rising: bool
               ) -> tuple[np.ndarray, np.ndarray]:
    """``n`` points evenly spaced on the axis ``x`` (pressure or volume) from end / n to
    the FE curve's end, and the FE's angle there (linear between its points): the part up
    to LIMIT_ANGLE_DEG, and with ``rising`` up to the first point where x stops rising."""
    keep = np.abs(angle_deg) <= LIMIT_ANGLE_DEG
    x, a = x[keep], angle_deg[keep]
    if rising and np.any(np.diff(x) <= 0):
        k = int(np.argmax(np.diff(x) <= 0))
        x, a = x[:k + 1], a[:k + 1]
    q = np.linspace(x[-1] / n, x[-1], n)
    return q, np.interp(q, x, a)


def curve_scores(emulator, paths: tuple[str, ...], even: int | None = None
                 ) -> dict[str, list[tuple[bool, float, float]]]:
    """Per axis ("pressure", "volume"): (FE curve complete, RMSE, max |error|) in deg over
    the answered points of every default-FE free-tip curve in ``paths`` (at the FE's
    points, or at ``even`` lab points: ``lab_points``); refused designs under "refused"
    as (complete, nan, nan)."""
    out: dict[str, list[tuple[bool, float, float]]] = {"pressure": [], "volume": [],
                                                        "refused": []}
    for path in paths:
        with CurveStore(path) as db:
            for rec in db.records():
                c = rec.curve
                if (rec.settings != SolverSettings() or rec.settings.tip != "free"
                        or c is None or len(c.pressure_pa) < 3):
                    continue
                complete = bool(abs(c.angle_deg[-1]) >= LIMIT_ANGLE_DEG - 1e-6)
                for axis, x, ask in (("pressure", c.pressure_pa, emulator.predict),
                                     ("volume", c.volume_ul, emulator.predict_volume)):
                    if even is None:
                        keep = (x > 0) & (np.abs(c.angle_deg) <= LIMIT_ANGLE_DEG)
                        at, fe = x[keep], c.angle_deg[keep]
                    else:
                        at, fe = lab_points(x, c.angle_deg, even, axis == "pressure")
                    try:
                        answer = ask(rec.design, at)
                    except InputError:
                        if axis == "pressure":
                            out["refused"].append((complete, np.nan, np.nan))
                        continue
                    err = np.asarray(answer.angle_deg, float) - fe
                    err = err[np.isfinite(err)]
                    if err.size:
                        out[axis].append((complete, float(np.sqrt(np.mean(err**2))),
                                          float(np.abs(err).max())))
                    elif even is not None:          # nothing answered: a miss
                        out[axis].append((complete, np.inf, np.inf))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--sets", nargs="+", default=list(DEFAULT_SETS))
    ap.add_argument("--even", type=int, default=None, metavar="N",
                    help="N lab points per curve, evenly spaced on each axis")
    args = ap.parse_args()
    if args.even is not None and args.even < 1:
        ap.error("--even N needs N >= 1")
    scores = curve_scores(load_emulator(args.emulator), tuple(args.sets), args.even)
    for axis in ("pressure", "volume"):
        rows = np.array(scores[axis], float).reshape(-1, 3)
        hit = (rows[:, 1] <= TARGET_RMSE_DEG) & (rows[:, 2] <= TARGET_MAX_DEG)
        for label, sel in (("complete FE curves", rows[:, 0] == 1),
                           ("early-ended FE curves", rows[:, 0] == 0)):
            print(f"by {axis}: {label}: {int(hit[sel].sum())} of {int(sel.sum())} within "
                  f"RMSE <= {TARGET_RMSE_DEG:g} and max <= {TARGET_MAX_DEG:g} deg "
                  f"(median per-curve RMSE {np.median(rows[sel, 1]):.2f} deg)")
    print(f"refused designs: {len(scores['refused'])}")


if __name__ == "__main__":
    main()
