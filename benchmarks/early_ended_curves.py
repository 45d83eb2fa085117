"""Would the database's early-ended FE curves help the emulator where they reach?

    python benchmarks/early_ended_curves.py --group "ecoflex_00_30/ecoflex_00_30-" \
        [--fraction 0.9] [--max-angle 50] [--axis volume] [--sets A.h5 B.h5 ...]

The emulator's curve GPs are fitted on the complete curves of a group (0 to 90 deg); a
curve that ended early (the FE's volume stop, a Newton failure) only bounds the FE range
(``database_rows.collect_rows``). This check fits, node by node, one GP of log(p_k / theta_k) on the
complete curves and one on those plus every early-ended curve that reaches the node
(node angle <= ``fraction`` x the curve's end, nodes up to ``max_angle``), and compares
both on the FE curves of random designs that are not in the database (the band
calibration set and the three held-out sets): the angle at each FE pressure, read off the
node pressures (linear between nodes, up to the FE curve's own end), per curve: RMSE,
and the issue's target RMSE <= 1 deg and max <= 3 deg. Means only; no bands, no range.
``--axis volume`` does the same for the volume nodes as the emulator has them since
2026-12-05 (above 30 deg the log of their rise in log V, ``curve_gps``), read by injected
volume as a query reads them (a natural spline in log theta, ``emulator.volume_shape``).
The counts are printed for the test curves that reached 90 deg and those that ended early.
"""

from __future__ import annotations

import argparse

import numpy as np

from solver.design_space import locate
from solver.errors import InputError
from solver.settings import SolverSettings
from solver.store import CurveStore
from surrogate.emulator.curve_gps import anchor_index, node_outputs, rise_outputs
from surrogate.emulator.emulator import emulated_volume_ul
from surrogate.emulator.features import ANGLE_NODES_DEG, FINE_ANGLES_DEG, curve_features
from surrogate.emulator.gp import fit_gp

TEST_SETS = ("service/data/band-calibration.h5", "benchmarks/heldout/ho2028.h5",
             "benchmarks/heldout/ho2029.h5", "benchmarks/heldout/ho2030.h5")


def group_rows(path: str, group: str) -> list[tuple]:
    """(unit coordinates, log p node vector, end angle, reduced pressures, |angles|) of
    the default-FE free-tip curves of ``group`` (with its bending sign) in ``path``."""
    out = []
    with CurveStore(path) as db:
        for rec in db.records():
            c = rec.curve
            if rec.settings != SolverSettings() or c is None or len(c.pressure_pa) < 3:
                continue
            try:
                point = locate(rec.design, reduced=True)
            except InputError:
                continue
            f = curve_features(c.pressure_pa / point.pressure_scale,
                               c.volume_ul / point.length_scale**3, c.angle_deg)
            if point.group + ("+" if f.sign > 0 else "-") != group:
                continue
            out.append((point.coordinates(), f.log_p, f.end_angle_deg,
                        c.pressure_pa / point.pressure_scale, f.sign * c.angle_deg,
                        f.log_v, c.volume_ul / point.length_scale**3))
    return out


def by_volume(row: tuple) -> tuple:
    """``row`` with the volume nodes as the GPs take them (the rise above the anchor) in
    place of log p, and the reduced injected volumes in place of the pressures."""
    n = len(ANGLE_NODES_DEG)
    z = rise_outputs(np.concatenate((row[1], row[5])), anchor_index())[n:]
    return (row[0], z, row[2], row[6], row[4])


def complete(row: tuple) -> bool:
    return row[2] >= 90.0 - 1e-9 and bool(np.isfinite(row[1]).all())


def node_means(train: list, test_u: np.ndarray, fraction: float, max_angle: float,
               with_partial: bool) -> np.ndarray:
    """Each node's GP mean of log(p/theta) at ``test_u``."""
    full = [r for r in train if complete(r)]
    out = np.empty((len(test_u), len(ANGLE_NODES_DEG)))
    warm = None
    for k, node in enumerate(ANGLE_NODES_DEG):
        rows = list(full)
        if with_partial and node <= max_angle:
            rows += [r for r in train if not complete(r) and np.isfinite(r[1][k])
                     and node <= fraction * r[2]]
        gp = fit_gp(np.array([r[0] for r in rows]), np.array([r[1][k] for r in rows]),
                    starts=2, seed=k, warm=warm)
        warm = gp
        out[:, k] = gp.predict(test_u)[0]
    return out


def volume_nodes_ul(z_means: np.ndarray) -> np.ndarray:
    """The emulated V(theta) at FINE_ANGLES_DEG from the GP means of the volume nodes as
    the GPs take them, as a query draws it."""
    n = len(ANGLE_NODES_DEG)
    log_v = node_outputs(np.concatenate((np.zeros(n), z_means)), np.zeros(2 * n),
                         anchor_index())[0][n:]
    return emulated_volume_ul(log_v)


def per_curve(test: list, means: np.ndarray, axis: str = "pressure"
              ) -> list[tuple[float, float, bool]]:
    """(RMSE, max, FE curve complete) of the angle read off the node pressures (or the
    emulated V(theta), ``axis`` "volume"), per test curve (deg)."""
    out = []
    for row, m in zip(test, means, strict=True):
        end, x, a = row[2], row[3], row[4]
        if axis == "pressure":
            nodes, angles = np.maximum.accumulate(ANGLE_NODES_DEG * np.exp(m)), ANGLE_NODES_DEG
        else:
            nodes, angles = volume_nodes_ul(m), FINE_ANGLES_DEG
        keep = (a <= min(90.0, end)) & (x > 0)
        if not keep.any():
            continue
        angle = np.interp(x[keep], np.r_[0.0, nodes], np.r_[0.0, angles])
        err = angle - a[keep]
        out.append((float(np.sqrt(np.mean(err**2))), float(np.abs(err).max()),
                    end >= 90.0 - 1e-9))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--group", required=True, help='emulator key, e.g. "pdms/ecoflex_00_30+"')
    ap.add_argument("--db", default="service/data/curves.h5")
    ap.add_argument("--fraction", type=float, default=1.0)
    ap.add_argument("--max-angle", type=float, default=90.0)
    ap.add_argument("--axis", choices=("pressure", "volume"), default="pressure")
    ap.add_argument("--sets", nargs="+", default=list(TEST_SETS))
    args = ap.parse_args()
    train = group_rows(args.db, args.group)
    test = [r for path in args.sets for r in group_rows(path, args.group)]
    test_u = np.array([r[0] for r in test])
    print(f"{args.group}: {sum(map(complete, train))} complete and "
          f"{sum(not complete(r) for r in train)} early-ended database curves; "
          f"{len(test)} test curves ({sum(not complete(r) for r in test)} early-ended)")
    if args.axis == "volume":
        train = [r for r in train if not complete(r) or np.isfinite(r[5]).all()]
        train, test = [by_volume(r) for r in train], [by_volume(r) for r in test]
    for label, partial in (("complete curves only", False), ("with early-ended", True)):
        res = per_curve(test, node_means(train, test_u, args.fraction, args.max_angle,
                                         partial), args.axis)
        rmse = np.array([r for r, _, _ in res])
        ok = [r <= 1 and m <= 3 for r, m, _ in res]
        full = [c for _, _, c in res]
        hit_full = sum(o and c for o, c in zip(ok, full))
        hit_early = sum(o and not c for o, c in zip(ok, full))
        print(f"  {label}, by {args.axis}: within target {sum(ok)} of {len(res)} (FE curve "
              f"complete {hit_full} of {sum(full)}, ended early {hit_early} of "
              f"{len(full) - sum(full)}), per-curve RMSE median {np.median(rmse):.2f} deg, "
              f"RMS over curves {np.sqrt(np.mean(rmse**2)):.2f} deg")


if __name__ == "__main__":
    main()
