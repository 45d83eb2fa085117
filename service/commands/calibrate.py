"""``balloon calibrate DATA.csv --report report.json [--plot report.png] [--save NAME]
[--model emulator|exponential|paper|PATH] [--strict]``: close the loop with measured
data.

Runs the calibration loop of ``surrogate.calibration`` (docs/calibration.md): the model
as is, the recalibrated baseline (cross-validated by curve), the candidate effects, the
selection and what is left; writes the JSON report, optionally the plot,
and optionally saves the augmented model under NAME in the models directory (usable as
``model`` in /v1/predict).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from service.commands.numbers import checked_int, int_action

#: folds of the grouped cross-validation, lo <= folds <= hi (POST /v1/calibrate's too)
FOLDS = (2, 50)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "calibrate", help="find what the model misses in measured data, and fix it",
        description="Calibrate a model (default: the design-space emulator) against "
                    "measured curves (CSV or JSON rows; columns in docs/measured-data.md), "
                    "test the catalogue of physical effects, and report the error before "
                    "and after.")
    parser.add_argument("data", type=Path, help="measured data, CSV (or .json rows)")
    parser.add_argument("--report", type=Path, required=True, help="report JSON to write")
    parser.add_argument("--plot", type=Path, help="PNG: data, model before/after, residuals")
    parser.add_argument("--save", metavar="NAME", help="save the augmented model as NAME")
    parser.add_argument("--model", default="emulator",
                        help="baseline: 'emulator' (default: the design-space emulator, "
                             "nothing left open), 'exponential' / 'fitted' (the fitted "
                             "exponential model), 'paper' (the paper's constants), a saved "
                             "model's name, or a model file")
    parser.add_argument("--models-dir", type=Path,
                        help="where --save writes (default: the service's models_dir)")
    int_action(parser.add_argument("--folds", type=int, default=5,
                                   help="folds of the grouped cross-validation by curve "
                                        "(default 5)"), "folds", *FOLDS)
    parser.add_argument("--strict", action="store_true",
                        help="refuse data that only get a warning otherwise (pressures that "
                             "look like kPa, duplicated rows)")
    parser.set_defaults(func=run)


def _starting_model(name: str):
    """The baseline named by --model, resolved as ``balloon predict`` resolves it."""
    from service.commands.predict import surrogate_from_args

    return surrogate_from_args(argparse.Namespace(model=name, form=None))


def _deg(value: float | None, missing: str = "n/a") -> str:
    """A report figure in degrees; the report has null where a figure is not defined
    (no noise floor without replicates, a non-finite error)."""
    return missing if value is None else f"{value:.2f}"


def _missing_from(directory: Path) -> list[Path]:
    """The directories ``mkdir(parents=True)`` would make for ``directory``, deepest
    first: none when it exists."""
    missing = []
    for d in (directory, *directory.parents):
        if d.exists():
            break
        missing.append(d)
    return missing


def _remove_if_empty(made: list[Path]) -> None:
    """Remove the directories this command made (``_missing_from``, deepest first) that
    are still empty: a refused save leaves no empty models directory behind."""
    for d in made:
        try:
            d.rmdir()
        except OSError:         # not empty (something else was put there), or gone
            return


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from service.commands.outputs import PLOT_SUFFIXES, check_output, distinct_outputs
    from solver.atomic_file import atomic_output, write_text_atomic
    from solver.errors import InputError
    from surrogate.calibration import (
        jsonable,
        load_observations,
        plot_calibration,
        run_calibration,
        save_model,
    )

    checked_int("--folds", args.folds, "folds", *FOLDS)
    try:        # the report's directory is made if need be; both outputs checked now
        args.report.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError("--report", f"directory {args.report.parent} cannot be made "
                         f"({exc.strerror or type(exc).__name__})",
                         "a path in a writable directory") from None
    data = (("the data file", args.data),)
    check_output(args.report, "--report", inputs=data)
    check_output(args.plot, "--plot", PLOT_SUFFIXES, inputs=data)
    distinct_outputs((("--report", args.report), ("--plot", args.plot)))
    obs = load_observations(args.data, strict=args.strict)  # validates before any work
    if args.save is not None:  # a bad or taken name ("" too) is refused before the work
        from service.models import check_new_model_name
        from surrogate.calibration._saved import ModelExistsError, _check_name

        try:
            _check_name(args.save)
        except InputError as exc:          # the option the user typed, not "name"
            raise InputError("--save", exc.detail, exc.allowed) from None
        if args.models_dir is None:
            from service.settings import get_settings

            args.models_dir = get_settings().models_dir
        if args.models_dir.exists() and not args.models_dir.is_dir():
            raise InputError("--models-dir", f"{args.models_dir} is not a directory",
                             "a directory for saved models (made if missing)")
        made = _missing_from(args.models_dir)   # removed again if nothing is saved
        try:        # made and tried now, not after the calibration's work
            args.models_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError("--models-dir", f"{args.models_dir} cannot be made "
                             f"({exc.strerror or type(exc).__name__})",
                             "a directory for saved models (made if missing)") from None
        check_output(args.models_dir / f"{args.save}.json", "--models-dir")
        if (args.models_dir / f"{args.save}.json").exists():
            raise ModelExistsError(args.save)
        check_new_model_name(args.save, args.models_dir)  # "PAPER", or "lab1" beside "Lab1"
    model = _starting_model(args.model)
    with tqdm(desc="calibrating", unit="fit", file=sys.stderr, leave=False) as bar:
        cal = run_calibration(obs, model, folds=args.folds, progress=lambda: bar.update())
    report = jsonable(cal.report)
    write_text_atomic(args.report, json.dumps(report, indent=1) + "\n")  # whole or not
    if args.plot:
        with atomic_output(args.plot, keep_suffix=True) as tmp:
            plot_calibration(cal, tmp)

    def deg(x: float | None) -> str:
        return "n/a" if x is None else f"{x:.2f}"

    for w in report["warnings"]:
        print(f"warning: {w}", file=sys.stderr)
    print(f"angle error: the model as is {deg(report['rmse_model_deg'])} deg RMS; "
          f"cross-validated {report['cross_validation']['method'].split('K-fold ')[-1]}, "
          f"the recalibrated baseline {deg(report['rmse_before_deg'])}"
          f" deg and with the selected effects {deg(report['rmse_after_deg'])} deg (noise "
          f"floor {deg(report['noise_floor_deg'])} deg); selected: "
          f"{', '.join(report['selected_effects']) or 'none'}"
          f"{'; RESIDUAL STRUCTURE REMAINS' if report['residual_structured_after'] else ''}")
    if report.get("rmse_pressure_before_pa") is not None:   # read by injected volume
        print(f"gauge pressure error (cross-validated): {report['rmse_pressure_before_pa']:.0f} "
              f"Pa before, {report['rmse_pressure_after_pa']:.0f} Pa after")
    print(report["interpretation"])
    if args.save is not None:   # the report, plot and summary come whatever the save does
        check_new_model_name(args.save, args.models_dir)  # one saved meanwhile
        try:        # save_model refuses what the saved formats cannot stand for (saveable)
            path = save_model(cal, args.save, args.models_dir)
        except InputError as exc:
            _remove_if_empty(made)
            if exc.field != "save":
                raise
            raise InputError("--save", f"{exc.detail}; the report is written to "
                             f"{args.report.name}", exc.allowed) from None
        print(f"saved model {args.save!r} to {path}", file=sys.stderr)
    return 0
