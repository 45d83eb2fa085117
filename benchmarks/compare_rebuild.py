"""A database rebuilt on new settings against its source, design by design.

For every record of the rebuilt database (``balloon precompute ... --designs-from SOURCE``)
the source record of the same design and tip: status and end angle on both, the curves
that ended early on one mesh only, and for free tips complete on both the pressure at 10 /
30 / 60 deg (PCHIP on the rising branch above 2 deg) of the rebuilt curve relative to the
source's. The figures a switch of the solver's defaults changes in the shipped data.

    python benchmarks/compare_rebuild.py --db REBUILT.h5 --source SOURCE.h5 \\
        --source-mesh former

(the switch to the balanced mesh: the shipped database against the former one,
benchmarks/RESULTS.md, "Issue 12, sixteenth session")
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np
from scipy.interpolate import PchipInterpolator

from solver.store import CurveStore, record_key

ANGLES_DEG = (10.0, 30.0, 60.0)


def pressure_at(curve, angles) -> np.ndarray:
    """Pressure (Pa) at |angle| = ``angles`` on the rising branch; NaN past it."""
    a, p = np.abs(curve.angle_deg), curve.pressure_pa
    falls = np.flatnonzero(np.diff(a) <= 0)
    rising = np.arange(len(a)) <= (falls[0] if len(falls) else len(a))
    keep = (a > 2.0) & rising
    out = np.full(len(angles), np.nan)
    if keep.sum() > 3:
        ok = np.asarray(angles) < a[keep].max()
        out[ok] = PchipInterpolator(a[keep], p[keep])(np.asarray(angles)[ok])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--db", required=True, help="the rebuilt database")
    ap.add_argument("--source", required=True, help="the database its designs came from")
    ap.add_argument("--source-mesh", default="former",
                    help="the source records' mesh_divisions (default: former)")
    args = ap.parse_args()
    rows = []
    with CurveStore(args.db) as new, CurveStore(args.source) as old:
        for rec in new.records():
            key = record_key(rec.design, replace(rec.settings, mesh_divisions=args.source_mesh))
            src = old.get(key)
            rows.append((rec, src))
    n = len(rows)
    same = sum(r.curve.status == s.curve.status for r, s in rows)
    print(f"{n} rebuilt records; status the same in {same}")
    for label, pick in (("failed here only", lambda r, s: r.curve.status == "failed"
                         and s.curve.status != "failed"),
                        ("failed in the source only", lambda r, s: s.curve.status == "failed"
                         and r.curve.status != "failed")):
        diff = [(r, s) for r, s in rows if pick(r, s)]
        print(f"{label}: {len(diff)}")
        for r, s in diff:
            d = r.design
            print(f"  {r.key[:12]} {d.body_material.id}/{d.membrane_material.id} "
                  f"L {d.L_mm:.2f} t {d.t_mm:.2f} {r.settings.tip}: end "
                  f"{float(r.curve.angle_deg[-1]) if len(r.curve) else float('nan'):.1f} deg "
                  f"(source {float(s.curve.angle_deg[-1]) if len(s.curve) else float('nan'):.1f})")
    ratios = []
    for r, s in rows:
        if (r.settings.tip == "free" and r.curve.status == s.curve.status == "complete"):
            ratios.append(pressure_at(r.curve, ANGLES_DEG) / pressure_at(s.curve, ANGLES_DEG))
    if ratios:
        pct = 100 * (np.array(ratios) - 1)
        for j, a in enumerate(ANGLES_DEG):
            col = pct[:, j][np.isfinite(pct[:, j])]
            if col.size:
                q = np.percentile(col, [5, 50, 95])
                print(f"pressure at {a:g} deg, rebuilt / source - 1 over {col.size} free "
                      f"curves: 5 / 50 / 95 % quantiles {q[0]:+.2f} / {q[1]:+.2f} / "
                      f"{q[2]:+.2f} %")


if __name__ == "__main__":
    main()
