"""The held-out curves outside the per-curve target: steep, or off in pressure?

    python benchmarks/heldout_pressure_error.py benchmarks/heldout/ho2028.h5 [more.h5 ...]

Per complete free-tip held-out FE curve: the shipped emulator's angle error at the FE's
own pressures (the issue's target: RMSE <= 1 and max <= 3 deg), its relative pressure
error at the FE's own angles (2 deg up to the emulated FE range, ``Emulator.inverse``),
and the curve's steepness, max over the curve of p d theta / d p (deg): where that is
large a small pressure error is a large angle error. Prints both groups' medians and
each curve outside the target.
"""

from __future__ import annotations

import argparse

import numpy as np

from solver.errors import InputError
from solver.store import CurveStore
from surrogate.emulator import load_emulator

LOWEST_ANGLE_DEG = 2.0   # below it a relative pressure error divides by ~nothing


def curve_errors(e, rec) -> tuple[float, float, float, float, float] | None:
    """(angle RMSE, angle max (deg), pressure RMS, pressure max (relative), steepness
    (deg)) of one held-out record, or None where the emulator refuses its design."""
    c = rec.curve
    keep = (np.abs(c.angle_deg) <= 90.0) & (c.pressure_pa > 0)
    p_fe, a_fe = c.pressure_pa[keep], c.angle_deg[keep]
    try:
        pred = e.predict(rec.design, p_fe)
    except InputError:
        return None
    ok = np.isfinite(pred.angle_deg)
    err = pred.angle_deg[ok] - a_fe[ok]
    limit = abs(pred.validity.get("fe_limit_angle_deg", 90.0))  # signed like the curve
    sel = (np.abs(a_fe[ok]) >= LOWEST_ANGLE_DEG) & (np.abs(a_fe[ok]) <= min(89.0, limit - 1e-6))
    rel = e.inverse(rec.design, a_fe[ok][sel]).pressure_pa / p_fe[ok][sel] - 1.0
    steep = np.gradient(np.abs(a_fe), p_fe) * p_fe
    return (float(np.sqrt(np.mean(err**2))), float(np.abs(err).max()),
            float(np.sqrt(np.mean(rel**2))) if rel.size else float("nan"),
            float(np.abs(rel).max()) if rel.size else float("nan"), float(steep.max()))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("heldout", nargs="+", help="held-out FE databases (HDF5)")
    ap.add_argument("--emulator", default="service/data/emulator.json")
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    rows = []
    for path in args.heldout:
        with CurveStore(path) as db:
            for rec in db.records():
                if rec.status == "complete" and rec.settings.tip == "free":
                    r = curve_errors(e, rec)
                    if r is not None:
                        rows.append(r)
    a = np.array(rows)
    within = (a[:, 0] <= 1.0) & (a[:, 1] <= 3.0)
    for name, s in (("within the target", within), ("outside", ~within)):
        if s.any():
            print(f"{name}: {int(s.sum())} curves; pressure error at the FE's angles, RMS "
                  f"median {100 * np.nanmedian(a[s, 2]):.2f} %, largest median "
                  f"{100 * np.nanmedian(a[s, 3]):.2f} %; steepness median "
                  f"{np.median(a[s, 4]):.0f} deg")
    for r in a[~within]:
        print(f"  outside: angle RMSE {r[0]:.2f} max {r[1]:.2f} deg | pressure RMS "
              f"{100 * r[2]:.2f} % max {100 * r[3]:.2f} % | steepness {r[4]:.0f} deg")


if __name__ == "__main__":
    main()
