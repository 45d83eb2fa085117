"""The default mesh's error at the box's corners.

    python benchmarks/mesh_corners.py [BODY MEMBRANE]      (default pdms_1_10 ecoflex_00_30)

Each corner design (L 4 / 18, t 0.5 / 1.2, T 0.6 / 2.0 mm; b 1.7, h 0.2 mm, W 3 mm; the
layers' presets) is solved with the default mesh (the balanced level 0) and with four
membrane layers and twice the x divisions (the finest one-direction variant of the
twenty-second session: 0.39 / 0.92 deg RMSE / max from level 1 on the box's thickest
membrane), and the default is compared with it: the angle at the default curve's own
pressures, the pressure at the same angle (2 deg to 0.98 x where both reach). One line a
corner; 1-8 min a corner on one core (the finer solve dominates).
"""

from __future__ import annotations

import itertools
import sys
import time
from dataclasses import replace

import numpy as np

from solver import Design, SolverSettings
from solver.materials import get_material
from solver.mesh import BALANCED_DIVISIONS
from solver.stepping import inflate

CORNERS_MM = tuple(itertools.product((4.0, 18.0), (0.5, 1.2), (0.6, 2.0)))   # L, t, T
FINER = replace(BALANCED_DIVISIONS, membrane=4, x_refine=2)


def compare(default, finer) -> str:
    """The default curve against the finer one: angle at the default's pressures, pressure
    at the same angle."""
    top = min(np.abs(default.angle_deg).max(), np.abs(finer.angle_deg).max())
    keep = (default.pressure_pa > 0) & (np.abs(default.angle_deg) <= top)
    angle = np.interp(default.pressure_pa[keep], np.maximum.accumulate(finer.pressure_pa),
                      finer.angle_deg)
    d = default.angle_deg[keep] - angle
    sign = np.sign(default.angle_deg[np.argmax(np.abs(default.angle_deg))])
    theta = np.linspace(2.0, 0.98 * top, 20)
    p0 = np.interp(theta, np.maximum.accumulate(sign * default.angle_deg), default.pressure_pa)
    pf = np.interp(theta, np.maximum.accumulate(sign * finer.angle_deg), finer.pressure_pa)
    rel = 100.0 * (p0 / pf - 1.0)
    return (f"default - finer: angle rmse {np.sqrt(np.mean(d**2)):.2f} max {np.abs(d).max():.2f}"
            f" deg; pressure at the same angle {rel.min():+.1f} .. {rel.max():+.1f} %")


def main() -> None:
    body = sys.argv[1] if len(sys.argv) > 1 else "pdms_1_10"
    membrane = sys.argv[2] if len(sys.argv) > 2 else "ecoflex_00_30"
    for length, t, thick in CORNERS_MM:
        design = Design(L_mm=length, t_mm=t, T_mm=thick, b_mm=1.7, h_mm=0.2,
                        body_material=get_material(body),
                        membrane_material=get_material(membrane)).validated()
        curves, seconds = [], []
        for divisions in (BALANCED_DIVISIONS, FINER):
            t0 = time.perf_counter()
            curves.append(inflate(design, SolverSettings(), divisions=divisions)[0])
            seconds.append(time.perf_counter() - t0)
        (c0, cf), (s0, sf) = curves, seconds
        print(f"{body}/{membrane} L {length:4.1f} t {t:.1f} T {thick:.1f}: default {c0.status}"
              f" to {abs(c0.angle_deg[-1]):5.1f} deg ({s0:.0f} s), finer {cf.status} to "
              f"{abs(cf.angle_deg[-1]):5.1f} ({sf:.0f} s); {compare(c0, cf)}", flush=True)


if __name__ == "__main__":
    main()
