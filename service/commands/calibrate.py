"""``balloon calibrate DATA.csv --report report.json [--plot report.png] [--save NAME]
[--model fitted|paper|PATH]``: close the loop with measured data.

Runs the calibration loop of ``surrogate.calibration`` (docs/calibration.md): the model
as is, the recalibrated baseline (cross-validated by curve), the candidate effects, the
selection and the residual structure test; writes the JSON report, optionally the plot,
and optionally saves the augmented model under NAME in the models directory (usable as
``model`` in /v1/predict).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "calibrate", help="find what the model misses in measured data, and fix it",
        description="Calibrate the exponential model against measured curves (CSV or JSON "
                    "rows; columns in docs/measured-data.md), test the catalogue of "
                    "physical effects, and report the error before and after.")
    parser.add_argument("data", type=Path, help="measured data, CSV (or .json rows)")
    parser.add_argument("--report", type=Path, required=True, help="report JSON to write")
    parser.add_argument("--plot", type=Path, help="PNG: data, model before/after, residuals")
    parser.add_argument("--save", metavar="NAME", help="save the augmented model as NAME")
    parser.add_argument("--model", default="fitted",
                        help="starting model: 'fitted' (the service's surrogate), 'paper' "
                             "(the paper's constants) or a surrogate JSON path")
    parser.add_argument("--models-dir", type=Path,
                        help="where --save writes (default: the service's models_dir)")
    parser.add_argument("--folds", type=int, default=5,
                        help="folds of the grouped cross-validation by curve (default 5)")
    parser.set_defaults(func=run)


def _starting_model(name: str):
    if name == "paper":
        return "paper"
    from surrogate import load_surrogate

    if name == "fitted":
        from service.settings import get_settings

        return load_surrogate(get_settings().surrogate_path)
    return load_surrogate(Path(name))


def _deg(value: float | None, missing: str = "n/a") -> str:
    """A report figure in degrees; the report has null where a figure is not defined
    (no noise floor without replicates, a non-finite error)."""
    return missing if value is None else f"{value:.2f}"


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from solver.errors import InputError
    from surrogate.calibration import (
        jsonable,
        load_observations,
        plot_calibration,
        run_calibration,
        save_model,
    )

    if not 2 <= args.folds <= 50:
        raise InputError("--folds", f"got {args.folds}", "2 <= folds <= 50")
    obs = load_observations(args.data)  # validates everything before any work
    if args.save:  # a bad or taken name is refused before the work, not after it
        from surrogate.calibration._saved import ModelExistsError, _check_name

        _check_name(args.save)
        if args.models_dir is None:
            from service.settings import get_settings

            args.models_dir = get_settings().models_dir
        if (args.models_dir / f"{args.save}.json").exists():
            raise ModelExistsError(args.save)
    model = _starting_model(args.model)
    with tqdm(desc="calibrating", unit="fit", file=sys.stderr, leave=False) as bar:
        cal = run_calibration(obs, model, folds=args.folds, progress=lambda: bar.update())
    report = jsonable(cal.report)
    args.report.parent.mkdir(parents=True, exist_ok=True)
    args.report.write_text(json.dumps(report, indent=1) + "\n")
    if args.plot:
        plot_calibration(cal, args.plot)
    if args.save:
        path = save_model(cal, args.save, args.models_dir)
        print(f"saved model {args.save!r} to {path}", file=sys.stderr)
    print(f"rmse model {_deg(report['rmse_model_deg'])} deg, before "
          f"{_deg(report['rmse_before_deg'])}, after {_deg(report['rmse_after_deg'])} "
          f"(noise floor {_deg(report['noise_floor_deg'], 'n/a: no replicate curves')})"
          f"; selected: {', '.join(report['selected_effects']) or 'none'}"
          f"{'; RESIDUAL STRUCTURE REMAINS' if report['residual_structured_after'] else ''}")
    print(report["interpretation"])
    return 0
