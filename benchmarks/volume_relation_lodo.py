"""Leave-one-design-out error of the exponential surrogate's pressure-volume relation
(surrogate/exponential/volume_relation.py) on the shipped families, for the chosen
coordinates (1 / L, t) with the cubic kernel and for the alternatives it was chosen over.

    python benchmarks/volume_relation_lodo.py [--db service/data/curves.h5]
        [--surrogate service/data/surrogate.json]

The records are those the surrogate file was fitted from (its provenance's record keys,
free tip). Errors at the held-out design's own FE points: volume (ul; % from 5 deg on)
at the FE angle, angle (deg) at the FE volume.
"""

from __future__ import annotations

import argparse
import json
from unittest import mock

import numpy as np

from solver.store import CurveStore
from surrogate.exponential import volume_relation as vr


def family_curves(db: str, surrogate: str) -> dict[tuple[str, str], list[vr.VolumeCurve]]:
    keys = set(json.loads(open(surrogate, encoding="utf-8").read())["provenance"]["record_keys"])
    fams: dict[tuple[str, str], list[vr.VolumeCurve]] = {}
    with CurveStore(db, mode="r") as store:
        for r in store.records():
            if r.key in keys and r.settings.tip == "free":
                d = r.design
                fams.setdefault((d.body_material.id, d.membrane_material.id), []).append(
                    vr.VolumeCurve(d.L_mm, d.t_mm, np.asarray(r.curve.angle_deg),
                                   np.asarray(r.curve.volume_ul)))
    return fams


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--db", default="service/data/curves.h5")
    ap.add_argument("--surrogate", default="service/data/surrogate.json")
    args = ap.parse_args()
    fams = family_curves(args.db, args.surrogate)
    variants = [("1/L, cubic (used)", vr._coordinates, "cubic"),
                ("L, cubic", lambda d: d.copy(), "cubic"),
                ("1/L, thin plate", vr._coordinates, "thin_plate_spline"),
                ("L, thin plate", lambda d: d.copy(), "thin_plate_spline")]
    print("| coordinates, kernel | family | designs | volume RMSE (max) ul | RMS % (max) | "
          "angle RMSE (max) deg |\n|---|---|---|---|---|---|")
    for name, coords, kernel in variants:
        with mock.patch.object(vr, "_coordinates", coords), mock.patch.object(vr, "KERNEL",
                                                                               kernel):
            for (body, membrane), curves in sorted(fams.items()):
                rel = vr.fit_volume_relation(curves)
                if rel is None or "rmse_ul" not in rel.lodo:
                    continue
                lo = rel.lodo
                print(f"| {name} | {body}/{membrane} | {lo['n_designs']} | "
                      f"{lo['rmse_ul']:.2f} ({lo['max_error_ul']:.1f}) | "
                      f"{lo['rmse_percent']:.1f} ({lo['max_error_percent']:.1f}) | "
                      f"{lo['rmse_angle_deg']:.2f} ({lo['max_angle_error_deg']:.1f}) |")


if __name__ == "__main__":
    main()
