"""Would the database's early-ended FE curves help the emulator where they reach?

    python benchmarks/early_ended_curves.py --group "ecoflex_00_30/ecoflex_00_30-" \
        [--fraction 0.9] [--max-angle 50]

The emulator's curve GPs are fitted on the complete curves of a group (0 to 90 deg); a
curve that ended early (the FE's volume stop, a Newton failure) only bounds the FE range
(``build._collect``). This check fits, node by node, one GP of log(p_k / theta_k) on the
complete curves and one on those plus every early-ended curve that reaches the node
(node angle <= ``fraction`` x the curve's end, nodes up to ``max_angle``), and compares
both on the FE curves of random designs that are not in the database (the band
calibration set and the three held-out sets): the angle at each FE pressure, read off the
node pressures (linear between nodes, up to the FE curve's own end), per curve: RMSE,
and the issue's target RMSE <= 1 deg and max <= 3 deg. Means only; no bands, no range.
"""

from __future__ import annotations

import argparse

import numpy as np

from solver.design_space import locate
from solver.errors import InputError
from solver.settings import SolverSettings
from solver.store import CurveStore
from surrogate.emulator.features import ANGLE_NODES_DEG, curve_features
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
                        c.pressure_pa / point.pressure_scale, f.sign * c.angle_deg))
    return out


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


def per_curve(test: list, means: np.ndarray) -> list[tuple[float, float]]:
    """(RMSE, max) of the angle read off the node pressures, per test curve (deg)."""
    out = []
    for row, m in zip(test, means, strict=True):
        _, _, end, p, a = row
        nodes_pa = np.maximum.accumulate(ANGLE_NODES_DEG * np.exp(m))
        keep = (a <= min(90.0, end)) & (p > 0)
        if not keep.any():
            continue
        angle = np.interp(p[keep], np.r_[0.0, nodes_pa], np.r_[0.0, ANGLE_NODES_DEG])
        err = angle - a[keep]
        out.append((float(np.sqrt(np.mean(err**2))), float(np.abs(err).max())))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--group", required=True, help='emulator key, e.g. "pdms/ecoflex_00_30+"')
    ap.add_argument("--db", default="service/data/curves.h5")
    ap.add_argument("--fraction", type=float, default=1.0)
    ap.add_argument("--max-angle", type=float, default=90.0)
    args = ap.parse_args()
    train = group_rows(args.db, args.group)
    test = [r for path in TEST_SETS for r in group_rows(path, args.group)]
    test_u = np.array([r[0] for r in test])
    print(f"{args.group}: {sum(map(complete, train))} complete and "
          f"{sum(not complete(r) for r in train)} early-ended database curves; "
          f"{len(test)} test curves ({sum(not complete(r) for r in test)} early-ended)")
    for label, partial in (("complete curves only", False), ("with early-ended", True)):
        res = per_curve(test, node_means(train, test_u, args.fraction, args.max_angle,
                                         partial))
        rmse = np.array([r for r, _ in res])
        ok = sum(r <= 1 and m <= 3 for r, m in res)
        print(f"  {label}: within target {ok} of {len(res)}, per-curve RMSE median "
              f"{np.median(rmse):.2f} deg, RMS over curves {np.sqrt(np.mean(rmse**2)):.2f} deg")


if __name__ == "__main__":
    main()
