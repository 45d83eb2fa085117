"""The emulator's part of ``balloon fit``: read the database, fit, save, summarise."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

from solver.store import CurveStore
from solver.store.record import git_commit, package_version
from surrogate.emulator.build import fit_emulator
from surrogate.emulator.file import save_emulator


def fit_and_save(db_path: str | Path, output: str | Path, level: float = 0.95
                 ) -> Iterator[str]:
    """Fit the emulator to ``db_path``, write it to ``output``; yields summary lines."""
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
    yield ""
    yield (f"{'emulator pair':32s} {'designs':>7s} {'failed':>6s} {'comp':>4s} "
           f"{'LOO rmse deg':>12s} {'LOO max deg':>11s} {'band x':>7s} {'LOO cover':>9s} "
           f"{'force designs':>13s}")
    for pair, rep in emulator.report["pairs"].items():
        if not rep.get("fitted"):
            yield f"{pair:32s} {rep.get('designs', 0):7d}  (too few complete curves: not fitted)"
            continue
        yield (f"{pair:32s} {rep['designs']:7d} {rep['failed_designs']:6d} "
               f"{rep['components']:4d} {rep['loo_rmse_deg']:12.2f} {rep['loo_max_deg']:11.2f} "
               f"{rep['band_scale']:7.2f} {rep['loo_coverage']:9.3f} {rep['force_designs']:13d}")
    yield f"emulator fitted in {fit_s:.1f} s; wrote {path}"
