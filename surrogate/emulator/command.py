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
from surrogate.fit_provenance import database_entry


def fit_and_save(db_path: str | Path, output: str | Path, level: float = 0.95,
                 calibration_db: str | Path | None = None, command: str = ""
                 ) -> tuple[Emulator, list[str]]:
    """Fit the emulator to ``db_path``, write it to ``output``; the emulator and summary
    lines (one per material group and bending side). With ``calibration_db`` (FE curves
    of random designs of the box, none of them in ``db_path``), the bands are calibrated
    on those too (``random_calibration``). ``command`` (the fit's command line) and each
    input database's checksum go into the file's provenance (``surrogate.fit_provenance``)."""
    t0 = time.perf_counter()
    with CurveStore(db_path) as db:
        records = list(db.records(status=None))
        generator = db.metadata.get("generator_command", "")
    provenance = fit_provenance(db_path, len(records), generator, command, calibration_db)
    emulator = fit_emulator(records, name="emulator", level=level, provenance=provenance)
    if calibration_db is not None:
        emulator = _calibrate(emulator, calibration_db, level)
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
    nodes = emulator.report.get("variance_nodes") or {}
    if nodes.get("chosen"):
        lines.append(f"variance exact at pressure nodes {nodes['nodes']}, the others read off "
                     f"their spline: on {nodes['check_designs']} other random designs within "
                     f"{100 * nodes['check_largest_rel_sd_error']:.1f} % (median "
                     f"{100 * nodes['check_median_rel_sd_error']:.1f} %) of the exact sd")
    elif nodes.get("shared_kernel"):
        lines.append("the pressure nodes share one kernel per group (or one below 45 deg, "
                     "the top pressure GPs' one above): their variance is exact at every "
                     "node, one product per kernel per query")
    cal = emulator.report.get("random_design_calibration")
    if cal:
        lines.append(random_calibration_lines(cal))
    force_cal = emulator.report.get("random_design_force_calibration")
    if force_cal:
        lines.append(force_calibration_line(force_cal))
    lines.append(f"emulator fitted in {fit_s:.1f} s; wrote {path}")
    return emulator, lines


def fit_provenance(db_path: str | Path, n_records: int, generator: str, command: str,
                   calibration_db: str | Path | None = None) -> dict[str, object]:
    """The emulator file's provenance: the code (version, commit), when, the command that
    reproduces the fit, and each input database by name, records and checksum
    (``surrogate.fit_provenance``)."""
    provenance: dict[str, object] = {
        "database_name": Path(db_path).name, "database_records": n_records,
        "database_command": generator, "package_version": package_version(),
        "git_commit": git_commit(),
        "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "fit_command": command, "database": database_entry(db_path, n_records)}
    if calibration_db is not None:
        with CurveStore(calibration_db) as db:
            n_calibration = len(db.keys())
        provenance["band_calibration_database"] = database_entry(calibration_db,
                                                                 n_calibration)
    return provenance


def _calibrate(emulator: Emulator, calibration_db: str | Path, level: float) -> Emulator:
    """``calibrate_on_random_designs`` on the curves of ``calibration_db``; its records
    must not be in the fit's database (``read_calibration_db``)."""
    from surrogate.emulator.force_calibration import calibrate_force_on_random_designs
    from surrogate.emulator.random_calibration import calibrate_on_random_designs

    fitted = {k for pe in emulator.pairs.values() for k in pe.keys}
    records, commands = read_calibration_db(calibration_db, fitted)
    source = {"database_name": Path(calibration_db).name, "database_records": len(records),
              "database_commands": commands}
    # the angle bands first: the force band is carried through the free tip's angle band
    emulator = calibrate_on_random_designs(emulator, records, level, source=source)
    return calibrate_force_on_random_designs(emulator, records, level, source=source)


def read_calibration_db(path: str | Path, fitted_keys: set[str]
                        ) -> tuple[list, list[str]]:
    """The records of the band-calibration database at ``path`` and the commands of its
    runs; InputError naming ``--band-calibration-db`` when it is not a curve database,
    holds no free-tip curve of the default FE, or shares a record with ``fitted_keys``."""
    from solver.errors import InputError
    from solver.settings import SolverSettings

    try:
        with CurveStore(path) as db:
            # the keys first (a status attribute a record, 0.6 s for 2403): a fitted
            # database given by mistake is refused before its curves are read (~30 s)
            shared = sum(1 for k in db.statuses() if k in fitted_keys)
            if shared:
                raise InputError("--band-calibration-db", f"{shared} of its curves are in "
                                 "the fitted database", "FE curves of designs the database "
                                 "does not hold")
            records = list(db.records())
            commands = [r.get("command", "") for r in db.metadata.get("runs", [])]
    except InputError as exc:   # not a curve database, or damaged
        if exc.field == "--band-calibration-db":
            raise
        raise InputError("--band-calibration-db", exc.detail, exc.allowed) from None
    if not any(r.settings == SolverSettings() for r in records):
        raise InputError("--band-calibration-db", f"{Path(path).name} holds no free-tip "
                         "curve of the default FE", "FE curves of random designs of the box "
                         "(benchmarks/heldout_designs.py)")
    return records, commands


def random_calibration_lines(cal: dict) -> str:
    """The random designs' calibration in a few lines: factors and coverage by axis."""
    out = [f"bands calibrated on {cal['curves']} random-design FE curves "
           f"({cal['source'].get('database_name', '?')}), factor per angle bin "
           f"{', '.join(f'{a:g}' for a in cal['bins_deg'])} deg:"]
    for axis, f in cal["factors"].items():
        before, after = cal["coverage_before"][axis], cal["coverage_after"][axis]
        out.append(f"  by {axis}: far {' '.join(f'{x:.2f}' for x in f['far'])}, near x "
                   f"{' '.join(f'{x:.2f}' for x in f['near'])}; coverage {before['all']:.3f}"
                   f" -> {after['all']:.3f} (far {before['far']:.3f} -> {after['far']:.3f}, "
                   f"near {_fmt(before['near'])} -> {_fmt(after['near'])})")
    for key, g in cal.get("group_factors", {}).items():
        own = [f"{axis} {side}" for axis, f in g.items() for side in ("far", "near")
               if f[side] != cal["factors"][axis][side]]
        if own:
            out.append(f"  {key}, its own points: " + "; ".join(
                f"{axis} {side} {' '.join(f'{x:.2f}' for x in g[axis][side])}"
                for axis, side in (o.split() for o in own)))
    return "\n".join(out)


def force_calibration_line(cal: dict) -> str:
    """The force band's calibration on random blocked-tip designs in one line."""
    if not cal.get("curves"):
        return f"force bands not calibrated on random designs: {cal.get('note', '')}"
    before, after = cal["coverage_before"]["all"], cal["coverage_after"]["all"]
    factors = ", ".join(f"{k} {v:.2f} ({cal['factor_source'][k]})"
                        for k, v in cal["factors"].items())
    return (f"force bands calibrated on {cal['curves']} random blocked-tip FE curves, "
            f"half-widths x {factors}; coverage {_fmt(before['coverage'])} -> "
            f"{_fmt(after['coverage'])} of {after['points']} points")


def _fmt(x: float | None) -> str:
    return "-" if x is None else f"{x:.3f}"


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
