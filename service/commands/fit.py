"""``balloon fit --db curves.h5 -o surrogate.json [--emulator-output emulator.json]``: fit
the models.

With ``--emulator-output``, fits the design-space emulator (the default predictor) to every
default-FE curve of the database in the box, with leave-one-out errors and calibrated
bands (docs/surrogate.md). Always fits the paper's exponential model (and the extended
form) to every family of the curve database, with leave-one-design-out errors and band
coverage; writes the versioned
surrogate JSON (which embeds the full fit report) and, with ``--report-dir``, report.json
and PNG plots (FE curves against the models, A against L, tau against t).
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("fit", help="fit the surrogate model to a curve database",
                                   description=__doc__.split("\n\n")[0].replace("``", ""))
    parser.add_argument("--db", required=True, metavar="PATH", help="curve database (HDF5)")
    parser.add_argument("-o", "--output", required=True, metavar="PATH",
                        help="surrogate file to write (JSON)")
    parser.add_argument("--emulator-output", metavar="PATH",
                        help="also fit the design-space emulator and write it here (JSON)")
    parser.add_argument("--band-calibration-db", metavar="PATH",
                        help="with --emulator-output: FE curves of random designs of the box, "
                             "not in --db, on which the emulator's bands are calibrated too "
                             "(the shipped one: service/data/band-calibration.h5)")
    parser.add_argument("--report-dir", metavar="DIR", help="also write report.json and PNGs")
    parser.add_argument("--name", default="fe-fit", help="the surrogate's name")
    from service.commands.numbers import allowed_action
    from surrogate.band_level import LEVEL_RANGE

    allowed_action(parser.add_argument("--level", type=float, default=0.95,
                                       help="band level for the coverage check (default 0.95)"),
                   LEVEL_RANGE)
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def _check_arguments(args: argparse.Namespace) -> None:
    """Refuse a band level and output paths that cannot work before reading the database
    and fitting (minutes on a full one), as ``balloon solve`` does."""
    from service.commands.outputs import check_output, check_output_dir, distinct_outputs
    from solver.errors import InputError
    from surrogate.band_level import z_value

    try:
        z_value(args.level)
    except InputError as exc:
        raise InputError("--level", exc.detail, exc.allowed) from None
    for flag, name in (("--output", args.output), ("--emulator-output", args.emulator_output)):
        check_output(name, flag, inputs=(("--db", args.db),
                                          ("--band-calibration-db", args.band_calibration_db)))
    distinct_outputs((("--output", args.output), ("--emulator-output", args.emulator_output),
                      ("--report-dir", args.report_dir and Path(args.report_dir) / "report.json")))
    if args.band_calibration_db is not None:
        if args.emulator_output is None:
            raise InputError("--band-calibration-db", "given without --emulator-output",
                             "use it with --emulator-output")
        if not Path(args.band_calibration_db).is_file():
            raise InputError("--band-calibration-db", f"no file {args.band_calibration_db}",
                             "an existing curve database (HDF5)")
        _check_calibration_db(args.band_calibration_db, args.db)
    check_output_dir(args.report_dir, "--report-dir")


def _check_calibration_db(path: str, fit_db: str) -> None:
    """The band-calibration database checked before the fit (which takes minutes), against
    the records of ``fit_db``; the fit checks it again against the curves it used."""
    from solver.errors import InputError
    from solver.store import CurveStore
    from surrogate.emulator.command import read_calibration_db

    try:
        with CurveStore(fit_db) as db:
            keys = set(db.keys())
    except (InputError, OSError):
        keys = set()                # --db's own check reports it
    read_calibration_db(path, keys)


# the fit's own field names -> the options that set them (an error names what was typed)
FIT_FLAGS = {"db": "--db", "level": "--level", "name": "--name"}


def run(args: argparse.Namespace) -> int:
    from solver.errors import InputError
    from surrogate import fit_surrogate, save_surrogate
    from surrogate.dataset import curves_from_store

    _check_arguments(args)
    try:
        curves, _ = curves_from_store(args.db)
        s = fit_surrogate(args.db, name=args.name, level=args.level,
                          progress=not args.no_progress and sys.stderr.isatty(),
                          command=command_line(args))
    except InputError as exc:
        raise InputError(FIT_FLAGS.get(exc.field, exc.field), exc.detail, exc.allowed
                         ) from None
    path = save_surrogate(s, args.output)
    print(summary_table(s))
    print(f"\nwrote {path}")
    if args.emulator_output:
        from surrogate.emulator.command import fit_and_save, side_by_side

        emulator, lines = fit_and_save(args.db, args.emulator_output, args.level,
                                       args.band_calibration_db, command=command_line(args))
        lines += side_by_side(s.report["families"], emulator)  # type: ignore[attr-defined]
        print("\n".join(lines))
    if args.report_dir:
        from surrogate.exponential.report_plots import write_report

        for p in write_report(s, curves, args.report_dir):
            print(f"wrote {p}")
    return 0


def command_line(args: argparse.Namespace) -> str:
    """The command that reproduces this fit (recorded in the files it writes), with the
    paths as given."""
    words = ["balloon", "fit", "--db", args.db, "-o", args.output]
    if args.emulator_output:
        words += ["--emulator-output", args.emulator_output]
    if args.band_calibration_db:
        words += ["--band-calibration-db", args.band_calibration_db]
    if args.name != "fe-fit":
        words += ["--name", args.name]
    if args.level != 0.95:
        words += ["--level", f"{args.level:g}"]
    return shlex.join(words)


def summary_table(s: object) -> str:
    """One row per family: default form, parameters, LODO RMSE, the band's calibration
    factor and the coverage of held-out interpolated designs before and after it."""
    rows = [f"{'family':44s} {'form':11s} {'a deg/mm':>9s} {'a_t Pa':>8s} {'b_t 1/mm':>8s} "
            f"{'LODO rmse exp/ext deg':>22s} {'band x':>6s} {'coverage raw/calibrated':>23s}"]
    for rep in s.report["families"]:  # type: ignore[attr-defined]
        form = rep["default_form"]
        v = rep["joint_fit"][form]["values"]
        lodo = rep["lodo"]

        def rmse(f: str, lodo: dict = lodo) -> str:
            d = lodo.get(f, {})
            return f"{d['rmse']:.2f}" if d.get("available") else "-"

        # Coverage of the held-out designs inside the range of the others.
        raw = lodo[form].get("coverage_interpolated")
        cal = lodo[form].get("coverage_calibrated_interpolated")
        cov_text = "/".join("-" if c is None else f"{c:.2f}" for c in (raw, cal))
        scale = lodo[form].get("band_scale")
        scale_text = "-" if scale is None else f"{scale:.2f}"
        rows.append(f"{rep['family']:44s} {form:11s} {v[0]:9.4f} {v[1]:8.1f} {v[2]:8.3f} "
                    f"{rmse('exponential') + ' / ' + rmse('extended'):>22s} "
                    f"{scale_text:>6s} {cov_text:>23s}")
    rows.append(f"force: {s.report.get('force')}")  # type: ignore[attr-defined]
    return "\n".join(rows)
