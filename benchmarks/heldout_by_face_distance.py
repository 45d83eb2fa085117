"""Held-out per-curve misses and band coverage against the design's distance to the box's
faces: is the emulator worse near the boundary of its box?

    python benchmarks/heldout_by_face_distance.py [--emulator service/data/emulator.json]
        [--sets benchmarks/heldout/ho*.h5]

Every complete free-tip FE curve of the sets is asked at its own pressures (``predict``,
per-curve target RMSE <= 1 and max <= 3 deg over its answered points) and its own angles
above 1 deg (``inverse``: the 95 % pressure band's coverage of the FE pressure). The
distance to a face is the smallest of min(u, 1 - u) over the design's six unit-cube
coordinates in its group (``BoxPoint.coordinates``: log scale, lengths at W = 3 mm, the
stiffness contrast); a face's own rows count designs within 0.08 of it.
"""

from __future__ import annotations

import argparse
import glob

import numpy as np

from solver.design_space import SAMPLED, locate
from solver.store import CurveStore
from surrogate.emulator import load_emulator

BINS = ((0.0, 0.05), (0.05, 0.1), (0.1, 0.2), (0.2, 0.5))
NEAR_FACE = 0.08


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--sets", nargs="+", default=sorted(glob.glob("benchmarks/heldout/ho*.h5")))
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    units, misses, inside, counted = [], [], [], []
    for path in args.sets:
        with CurveStore(path) as store:
            records = [r for r in store.records()
                       if r.status == "complete" and r.settings.tip != "blocked"]
        for rec in records:
            c = rec.curve
            keep = (np.abs(c.angle_deg) <= 90.0) & (c.pressure_pa > 0)
            p = e.predict(rec.design, c.pressure_pa[keep])
            ok = np.isfinite(p.angle_deg)
            if not ok.any():
                continue
            err = p.angle_deg[ok] - c.angle_deg[keep][ok]
            up = (np.abs(c.angle_deg) <= 90.0) & (np.abs(c.angle_deg) > 1.0)
            inv = e.inverse(rec.design, c.angle_deg[up])
            got = np.isfinite(inv.pressure_pa)
            fe_p = c.pressure_pa[up][got]
            units.append(locate(rec.design, reduced=True).coordinates())
            misses.append(bool(np.sqrt(np.mean(err**2)) > 1.0 or np.abs(err).max() > 3.0))
            inside.append(int(((fe_p >= inv.lower_pa[got]) & (fe_p <= inv.upper_pa[got])).sum()))
            counted.append(int(got.sum()))
    u, miss = np.array(units), np.array(misses)
    inside_n, counted_n = np.array(inside), np.array(counted)
    to_face = np.minimum(u, 1.0 - u).min(1)
    print(f"{len(miss)} complete held-out curves, {int(miss.sum())} outside the per-curve "
          f"target ({len(args.sets)} sets)")
    for lo, hi in BINS:
        sel = (to_face >= lo) & (to_face < hi)
        print(f"distance to the nearest face {lo:.2f}-{hi:.2f}: {int(sel.sum())} curves, "
              f"{int(miss[sel].sum())} missed ({miss[sel].mean() if sel.any() else 0:.2f}); "
              f"pressure band coverage {inside_n[sel].sum() / max(1, counted_n[sel].sum()):.3f}"
              f" of {int(counted_n[sel].sum())} points")
    for j, name in enumerate(SAMPLED):
        low, high = u[:, j] < NEAR_FACE, u[:, j] > 1.0 - NEAR_FACE
        print(f"{name}: low face {int(low.sum())} curves, missed {miss[low].mean():.2f}; "
              f"high face {int(high.sum())}, missed {miss[high].mean():.2f}")


if __name__ == "__main__":
    main()
