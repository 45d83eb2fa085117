"""Is the FE's curve a smooth function of the design where the emulator misses it?

    python benchmarks/fe_line_smoothness.py --set benchmarks/heldout/ho2033.h5 --L-mm 5.66
        [--field h_mm] [--scales 0.97,0.98,0.99,1,1.01,1.02,1.03]

Takes the free-tip curve of the held-out set's design whose chamber length is ``--L-mm``
(to 0.01 mm), solves the default FE at that design with one length (``--field``) scaled by
each of ``--scales``, reads each curve's pressure nodes as the emulator reads them
(``features.curve_features``: log(p / theta) at the fixed angles), fits a quadratic in log
(scale) through each node and prints the residuals (% of the pressure). A residual of a
few 0.001 % says the FE answers smoothly there, so an emulator error of 1-2 % in pressure
at that design is the interpolation's, not a jump of the FE's (the mesh's element counts,
a Newton tolerance, a branch change). Also printed: the re-solved curve at scale 1 against
the stored one (the solver of today against the set's).

One default-FE solve per scale: 10-60 s each on the 2-core VM.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from solver import solve
from solver.store import CurveStore
from surrogate.emulator.features import ANGLE_NODES_DEG, curve_features

SHOWN_DEG = (4.0, 30.0, 45.0, 60.0, 75.0, 90.0)


def node_log_p(curve) -> np.ndarray:  # noqa: ANN001 - a solver.Curve
    """The curve's pressure nodes, log(p_k / theta_k) at ANGLE_NODES_DEG (NaN past it)."""
    return curve_features(np.asarray(curve.pressure_pa), np.asarray(curve.volume_ul),
                          np.asarray(curve.angle_deg)).log_p


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--set", required=True, help="a held-out curve database (.h5)")
    ap.add_argument("--L-mm", type=float, required=True, help="the design's L (mm)")
    ap.add_argument("--field", default="h_mm", choices=("L_mm", "t_mm", "T_mm", "b_mm",
                                                         "h_mm"))
    ap.add_argument("--scales", default="0.97,0.98,0.99,1,1.01,1.02,1.03")
    args = ap.parse_args()
    scales = np.array([float(s) for s in args.scales.split(",")])
    with CurveStore(args.set) as store:
        record = next(r for r in store.records()
                      if abs(r.design.L_mm - args.L_mm) < 0.01 and r.settings.tip == "free")
    nodes = [int(np.flatnonzero(np.isclose(ANGLE_NODES_DEG, a))[0]) for a in SHOWN_DEG]
    log_p = []
    for k in scales:
        design = dataclasses.replace(record.design,
                                     **{args.field: getattr(record.design, args.field) * k})
        curve = solve(design, record.settings)
        log_p.append(node_log_p(curve))
        if k == 1.0:
            stored = node_log_p(record.curve)
            print("re-solved minus stored (%):",
                  np.round(100 * (log_p[-1] - stored)[nodes], 4))
        print(f"{args.field} x {k:g}: {len(curve.angle_deg)} steps", flush=True)
    log_p = np.array(log_p)
    x = np.log(scales)
    print(f"node (deg)  d log p / d log {args.field}   quadratic fit residuals (%)")
    for j, angle in zip(nodes, SHOWN_DEG, strict=True):
        y = log_p[:, j]
        ok = np.isfinite(y)
        if ok.sum() < 4:
            print(f"{angle:6.0f}  (reached by {ok.sum()} curves)")
            continue
        c = np.polyfit(x[ok], y[ok], 2)
        resid = 100 * (y[ok] - np.polyval(c, x[ok]))
        print(f"{angle:6.0f}  {c[1]:+.3f}   " + " ".join(f"{r:+.4f}" for r in resid))


if __name__ == "__main__":
    main()
