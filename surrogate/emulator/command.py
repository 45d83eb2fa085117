"""The emulator's part of ``balloon fit``: read the database, fit, save, summarise, and
set the emulator's held-out errors beside the exponential model's on the same curves."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from solver.store import CurveStore
from solver.store.record import git_commit, package_version
from surrogate.emulator.build import fit_emulator
from surrogate.emulator.emulator import Emulator
from surrogate.emulator.file import save_emulator


def fit_and_save(db_path: str | Path, output: str | Path, level: float = 0.95
                 ) -> tuple[Emulator, list[str]]:
    """Fit the emulator to ``db_path``, write it to ``output``; the emulator and summary
    lines (one per material group and bending side)."""
    t0 = time.perf_counter()
    with CurveStore(db_path) as db:
        records = list(db.records(status=None))
        generator = db.metadata.get("generator_command", "")
    provenance = {"database_name": Path(db_path).name, "database_records": len(records),
                  "database_command": generator, "package_version": package_version(),
                  "git_commit": git_commit(), "created_utc": time.strftime(
                      "%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    emulator = fit_emulator(records, name="emulator", level=level, provenance=provenance)
    fit_s = time.perf_counter() - t0
    path = save_emulator(emulator, output)
    lines = ["", f"{'emulator group':32s} {'designs':>7s} {'failed':>6s} {'comp':>4s} "
                 f"{'CV rmse deg':>12s} {'CV max deg':>11s} {'band x':>7s} "
                 f"{'CV cover':>9s} {'force designs':>13s}"]
    for pair, rep in emulator.report["pairs"].items():
        if not rep.get("fitted"):
            lines.append(f"{pair:32s} {rep.get('designs', 0):7d}  "
                         "(too few complete curves: not fitted)")
            continue
        lines.append(f"{pair:32s} {rep['designs']:7d} {rep['failed_designs']:6d} "
                     f"{rep['components']:4d} {rep['cv_rmse_deg']:12.2f} "
                     f"{rep['cv_max_deg']:11.2f} {rep['band_scale_median']:7.2f} "
                     f"{rep['cv_coverage']:9.3f} {rep['force_designs']:13d}")
    lines.append(f"emulator fitted in {fit_s:.1f} s; wrote {path}")
    return emulator, lines


def cv_rmse_by_key(emulator: Emulator) -> dict[str, float]:
    """Each database curve's cross-validated angle RMSE (deg; 5 folds, the emulator
    refitted without the curve's fold), by record key."""
    out: dict[str, float] = {}
    for pair, pe in emulator.pairs.items():
        per_curve = emulator.report["pairs"][pair].get("cv_curve_rmse_deg", [])
        out.update(zip(pe.keys, per_curve))
    return out


def side_by_side(families: list[dict], emulator: Emulator) -> list[str]:
    """Held-out angle RMSE (deg) per exponential family: the exponential model's
    leave-one-design-out figure and the emulator's 5-fold cross-validated figure on the same FE
    curves (the RMS of the per-curve RMSEs; curves the emulator does not hold, e.g. ones
    ending before 90 deg, are left out of its figure and counted)."""
    cv = cv_rmse_by_key(emulator)
    lines = ["", f"{'held-out angle rmse (deg)':44s} {'curves':>6s} {'exponential':>11s} "
                 f"{'emulator':>8s} {'emulator has':>12s}"]
    for fam in families:
        keys = fam.get("record_keys", [])
        mine = [cv[k] for k in keys if k in cv]
        exp_rmse = fam["lodo"]["exponential"].get("rmse")
        emu = f"{np.sqrt(np.mean(np.square(mine))):.2f}" if mine else "-"
        exp_text = "-" if exp_rmse is None else f"{exp_rmse:.2f}"
        lines.append(f"{fam['family']:44s} {len(keys):6d} {exp_text:>11s} {emu:>8s} "
                     f"{len(mine):>5d} of {len(keys):<4d}")
    return lines
