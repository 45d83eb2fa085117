"""``balloon predict --L-mm 7.1 --t-mm 0.5 --pressures 500 1000 1500 [--model paper|PATH|NAME]``:
bending angle (deg) with a prediction band from the surrogate, and validity flags.

The default model is service/data/surrogate.json when it exists, else the paper preset;
``--model NAME`` uses a calibrated model saved by ``balloon calibrate --save NAME`` (the
models directory: ``--models-dir``, default BALLOON_MODELS_DIR or ~/.balloon/models).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

DEFAULT_SURROGATE = Path(__file__).resolve().parents[1] / "data" / "surrogate.json"


def add_design_arguments(parser: argparse.ArgumentParser, required: bool = True) -> None:
    parser.add_argument("--L-mm", type=float, required=required, dest="L_mm",
                        help="chamber length, mm")
    parser.add_argument("--t-mm", type=float, required=required, dest="t_mm",
                        help="membrane thickness, mm")
    parser.add_argument("--T-mm", type=float, default=None, dest="T_mm",
                        help="body thickness above the chamber, mm (default 1)")
    parser.add_argument("--b-mm", type=float, default=None, dest="b_mm",
                        help="chamber width, mm (default 1.8)")
    parser.add_argument("--h-mm", type=float, default=None, dest="h_mm",
                        help="chamber height, mm (default 0.15)")
    # the flag names of `balloon solve`; --body and --membrane are kept as aliases
    parser.add_argument("--body-material", "--body", default=None, dest="body_material",
                        help="body material id (default pdms_1_10)")
    parser.add_argument("--membrane-material", "--membrane", default=None,
                        dest="membrane_material",
                        help="membrane material id (default ecoflex_00_30)")


def add_model_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", default=None, metavar="paper|PATH|NAME",
                        help="`paper`, a surrogate file, or the name of a saved calibrated "
                             "model (default: the bundled fit if present, else paper)")
    parser.add_argument("--models-dir", type=Path, default=None,
                        help="where saved calibrated models are (default: BALLOON_MODELS_DIR,"
                             " else ~/.balloon/models)")
    parser.add_argument("--form", choices=("exponential", "extended"), default=None,
                        help="model form (default: each family's fitted default)")
    parser.add_argument("--level", type=float, default=0.95, help="band level (0.95)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def design_from_args(args: argparse.Namespace) -> object:
    from solver.design import design_from_dict

    data = {k: getattr(args, k) for k in ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm")
            if getattr(args, k, None) is not None}
    if args.body_material:
        data["body_material"] = args.body_material
    if args.membrane_material:
        data["membrane_material"] = args.membrane_material
    return design_from_dict(data)


def saved_model_name(spec: str | None) -> str | None:
    """``spec`` if it names a saved calibrated model: a bare name (not "paper", not a path
    or a .json file)."""
    from surrogate.calibration._saved import NAME_PATTERN

    if (spec is None or spec == "paper" or spec.endswith(".json") or Path(spec).exists()
            or not NAME_PATTERN.match(spec)):
        return None
    return spec


def surrogate_from_args(args: argparse.Namespace) -> object:
    from solver.errors import InputError
    from surrogate import open_surrogate

    name = saved_model_name(args.model)
    if name is not None:
        from surrogate.calibration import load_model

        if args.form is not None:
            raise InputError("--form", f"the calibrated model {name!r} has one form",
                             "leave --form out with a saved model")
        models_dir = args.models_dir
        if models_dir is None:
            from service.settings import get_settings

            models_dir = get_settings().models_dir
        return load_model(name, models_dir)
    spec = args.model or (str(DEFAULT_SURROGATE) if DEFAULT_SURROGATE.is_file() else "paper")
    return open_surrogate(spec).with_form(args.form)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("predict", help="predict bending angles from the surrogate",
                                   description=__doc__.split("\n\n")[0].replace("``", ""))
    add_design_arguments(parser)
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--pressures", type=float, nargs="+", metavar="PA",
                       help="pressures, Pa")
    group.add_argument("--pressure-range", type=float, nargs=3, metavar=("START", "STOP", "NUM"),
                       help="NUM evenly spaced pressures from START to STOP, Pa")
    add_model_arguments(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from solver.errors import InputError

    design = design_from_args(args)
    s = surrogate_from_args(args)
    if args.pressures is not None:
        pressures = np.array(args.pressures)
    else:
        start, stop, num = args.pressure_range
        if not 1 <= num <= 100_000 or num != int(num):
            raise InputError("--pressure-range", f"NUM = {num:g}", "an integer 1..100000")
        pressures = np.linspace(start, stop, int(num))
    pred = s.predict(design, pressures, level=args.level)  # type: ignore[attr-defined]
    if args.json:
        print(json.dumps(pred.as_dict(), indent=1))
        return 0
    form = getattr(pred, "form", None) or "calibrated"  # a saved model has no form choice
    force = getattr(pred, "force_mn", None)
    print(f"model {pred.model} ({form}), L = {design.L_mm:g} mm, "  # type: ignore
          f"t = {design.t_mm:g} mm, band {100 * args.level:g} %")
    head = f"{'pressure_pa':>12s} {'angle_deg':>10s} {'lower_deg':>10s} {'upper_deg':>10s}"
    if force is not None:
        head += f" {'force_mn':>9s} {'lower_mn':>9s} {'upper_mn':>9s}"
    print(head)
    for i, p in enumerate(pred.pressure_pa):
        line = (f"{p:12.1f} {pred.angle_deg[i]:10.2f} {pred.lower_deg[i]:10.2f} "
                f"{pred.upper_deg[i]:10.2f}")
        if force is not None:
            line += (f" {pred.force_mn[i]:9.3f} {pred.force_lower_mn[i]:9.3f} "
                     f"{pred.force_upper_mn[i]:9.3f}")
        print(line)
    print_validity(pred.validity)
    return 0


def print_validity(validity: dict) -> None:
    if validity["in_domain"]:
        print("validity: inside the fitted domain")
    else:
        print("validity: " + ", ".join(validity["flags"]))
        for m in validity["messages"]:
            print(f"  - {m}")
