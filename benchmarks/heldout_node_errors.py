"""Where and how the emulator misses the held-out curves: its node errors, their tails and
the band's coverage by region.

    python benchmarks/heldout_node_errors.py [--emulator service/data/emulator.json]
        [--sets benchmarks/heldout/ho*.h5]

For each material group, every free-tip curve the held-out sets score
(``bench_emulator.scored``) is read as the emulator reads its database curves (pressure
nodes, log(p / theta) at the fixed angles, reduced to the box's terms) and compared with
the emulator's node means and sds at its design (``PairEmulator.curve_nodes``): per node
the mean, median and RMS error (% of the pressure) and the z-scores' RMS and share beyond
3 (the GP's own sd, before the band's calibrated multipliers). Then each curve is asked
as a user asks it (``predict`` at its FE pressures up to 90 deg) and counted, by group and
inside or outside the "stiff corner" (unit log coordinates L < 0.35, T > 0.6, b < 0.5:
short, narrow chambers under a thick body), as a miss of the per-curve target (RMSE > 1 or
max > 3 deg) and for its band's coverage of the FE points.
"""

from __future__ import annotations

import argparse
import collections

import numpy as np
from bench_emulator import scored_free_records

from solver.design_space import locate
from solver.errors import InputError
from surrogate.emulator import load_emulator
from surrogate.emulator.features import ANGLE_NODES_DEG, N_NODES, curve_features

SHOWN_DEG = (4.0, 30.0, 45.0, 60.0, 75.0, 90.0)


def in_stiff_corner(u: np.ndarray) -> bool:
    """Unit log coordinates (L, t, T, b, h, contrast) of a short, narrow chamber under a
    thick body: where the held-out misses gather."""
    return bool(u[0] < 0.35 and u[2] > 0.6 and u[3] < 0.5)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--emulator", default="service/data/emulator.json")
    ap.add_argument("--sets", nargs="+", default=None)
    args = ap.parse_args()
    e = load_emulator(args.emulator)
    errors: dict[str, list] = collections.defaultdict(list)
    counts: dict[tuple, list] = collections.defaultdict(lambda: [0, 0, 0, 0])
    for r in scored_free_records(args.sets):
        point = locate(r.design, reduced=True)
        u = point.coordinates()
        try:
            pair = e._pair(point, u)
            angle = np.asarray(r.curve.angle_deg)
            pressure = np.asarray(r.curve.pressure_pa)
            keep = (np.abs(angle) <= 90) & (pressure > 0)
            answer = e.predict(r.design, pressure[keep])
        except InputError:
            continue
        fe = curve_features(r.curve.pressure_pa / point.pressure_scale,
                            r.curve.volume_ul / point.length_scale**3, angle)
        mean, var, _, _ = pair.curve_nodes(u, slice(0, N_NODES))
        errors[point.group].append((mean[:N_NODES] - fe.log_p,
                                    np.sqrt(var[:N_NODES])))
        m = np.asarray(answer.angle_deg)
        ok = np.isfinite(m)
        if not ok.any():
            continue
        a = angle[keep][ok]
        err = m[ok] - a
        inside = ((a >= np.asarray(answer.lower_deg)[ok] - 1e-9)
                  & (a <= np.asarray(answer.upper_deg)[ok] + 1e-9))
        miss = bool(np.sqrt(np.mean(err**2)) > 1 or np.abs(err).max() > 3)
        for key in ((point.group, in_stiff_corner(u)), ("all", in_stiff_corner(u))):
            c = counts[key]
            c[0] += 1
            c[1] += miss
            c[2] += int(inside.sum())
            c[3] += inside.size
    nodes = [int(np.flatnonzero(np.isclose(ANGLE_NODES_DEG, a))[0]) for a in SHOWN_DEG]
    for group, rows in sorted(errors.items()):
        err = np.array([r[0] for r in rows])
        sd = np.array([r[1] for r in rows])
        print(f"{group}: {len(rows)} curves; node error in log p (%), z = error / GP sd")
        for j, angle in zip(nodes, SHOWN_DEG, strict=True):
            ok = np.isfinite(err[:, j])
            x, z = err[ok, j], err[ok, j] / sd[ok, j]
            print(f"  {angle:4.0f} deg  n {ok.sum():3d}  mean {100 * x.mean():+.3f}  median "
                  f"{100 * np.median(x):+.3f}  RMS {100 * np.sqrt(np.mean(x**2)):.3f}   "
                  f"z RMS {np.sqrt(np.mean(z**2)):.2f}  |z| > 3: {np.mean(np.abs(z) > 3):.3f}")
    print("group, in the stiff corner: curves, misses of the per-curve target, band coverage")
    for (group, corner), (n, miss, inside, points) in sorted(counts.items(), key=str):
        print(f"  {group:32s} {'corner' if corner else 'rest':6s} {n:4d} curves  {miss:3d} "
              f"misses ({miss / n:.2f})  coverage {inside / max(points, 1):.3f} of {points}")


if __name__ == "__main__":
    main()
