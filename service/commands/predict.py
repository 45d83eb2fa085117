"""``balloon predict --L-mm 7.1 --t-mm 0.5 --pressures 500 1000 1500 [--model NAME|PATH]``:
bending angle (deg) with a prediction band, force and injected volume, and validity flags;
asked by pressure, by injected volume (``--volumes 2 5 10``) or by time at a syringe pump's
flow rate (``--times 2 4 8 --flow-ul-s 2.5``); ``--inlet`` adds the pressure a gauge at
the pump reads (chamber + R Q, the paper's inlet channel, ``--tubing-mm`` for tubing).

The default model is the design-space emulator (service/data/emulator.json, or
BALLOON_EMULATOR_PATH); ``--model exponential``, ``paper``, a saved calibrated model's
name, or a model file's path select another. Pressures past the FE's range get no angle.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
from pathlib import Path

from service.cli import StoreOnce
from service.commands.numbers import (
    STIFFNESS_SCALE_LIMITS,
    allowed_action,
    attach_design_ranges,
    number_action,
)
from service.pump import AXES
from solver.number_text import NUMBER_FORM, WrittenNumber, ascii_float, unheld_words
from surrogate.band_level import ASKED_LEVEL_WORDS, ASKED_LEVELS
from surrogate.hydraulics import LIMITS as INLET_LIMITS
from surrogate.predictor import MAX_ASKED_VALUES
from surrogate.volume_control import FLOW_RANGE

#: ``--pressure-range START STOP NUM``'s values: the pressures' range, and at most as many
#: pressures as ``--pressures`` and an HTTP request's list take (``MAX_ASKED_VALUES``;
#: it took 100,000 until 2026-12-08)
_RANGE_ALLOWED = (f"{AXES['pressures_pa'][0]:g} <= START, STOP <= {AXES['pressures_pa'][1]:g} "
                  f"{AXES['pressures_pa'][2]}; NUM an integer 1..{MAX_ASKED_VALUES}, as "
                  "--pressures' values")

DEFAULT_SURROGATE = Path(__file__).resolve().parents[1] / "data" / "surrogate.json"


def number_list(text: str) -> list[float]:
    """One command-line word of numbers: ``1000`` or ``500,1000,1500`` (commas, as
    people paste them from a spreadsheet, or spaces between words). An empty place
    between two commas (``1,,2``: a spreadsheet's empty cell) is refused, not skipped:
    the numbers after it would move up by one."""
    items = []     # a word's one leading or trailing comma is no place ("1," "2")
    for word in text.split():
        places = word.split(",")
        items += places[places[0] == "":len(places) - (len(places) > 1 and places[-1] == "")]
    if "" in items:      # the parser adds the option's range (service.cli.Parser)
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a list of numbers (item {items.index('') + 1} is an empty "
            "place between two commas: a missing value?; give a number in each place)")
    words = text.replace(",", " ").split()
    try:
        numbers = [ascii_float(w) for w in words] if words else [float("nan")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a list of numbers (numbers in {NUMBER_FORM}, separated by "
            "spaces or commas)") from None
    unheld = [i for i, n in enumerate(numbers, start=1) if isinstance(n, WrittenNumber)]
    if unheld:     # 1e-400 Pa was answered as 0 Pa; a JSON body's list refuses it too
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a list of numbers (item {unheld[0]}: "
            f"{unheld_words(numbers[unheld[0] - 1])})")  # type: ignore[arg-type]
    return numbers


class NumberListAction(StoreOnce):
    """``nargs="+"`` of ``number_list`` words, flattened into one list of floats: at most
    MAX_ASKED_VALUES of them, the limit of the same list in an HTTP request; the option
    once (``--pressures 1000 --pressures 2000`` was 2000 Pa alone)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: object, option_string: str | None = None) -> None:
        self.once(parser, namespace)
        numbers = [v for word in values for v in word]  # type: ignore[attr-defined]
        if len(numbers) > MAX_ASKED_VALUES:
            parser.error(f"argument {option_string}: {len(numbers)} values (allowed: 1 to "
                         f"{MAX_ASKED_VALUES} values, as an HTTP request's list)")
        setattr(namespace, self.dest, numbers)


def add_number_list(parser: argparse._ActionsContainer, flag: str, metavar: str,
                    help: str, allowed: tuple[float, float, str]) -> None:
    """A list option whose values lie in ``allowed`` (low, high, unit): a word that is no
    list of numbers is told the range too (service.commands.numbers)."""
    number_action(parser.add_argument(flag, type=number_list, nargs="+",
                                      action=NumberListAction, metavar=metavar,
                                      help=f"{help} (spaces or commas between them)"),
                  *allowed)


def add_design_arguments(parser: argparse.ArgumentParser, required: bool = True) -> None:
    from solver.design_space import BOX_MM

    def box(name: str) -> str:   # the emulator's box (its own errors say it too)
        lo, hi = BOX_MM[name]
        return f"the emulator's box {lo:g} to {hi:g} at W = 3"

    parser.add_argument("--L-mm", type=float, required=required, dest="L_mm",
                        help=f"chamber length, mm ({box('L_mm')})")
    parser.add_argument("--t-mm", type=float, required=required, dest="t_mm",
                        help=f"membrane thickness, mm ({box('t_mm')})")
    parser.add_argument("--T-mm", type=float, default=None, dest="T_mm",
                        help=f"body thickness above the chamber, mm (default 1; {box('T_mm')})")
    parser.add_argument("--b-mm", type=float, default=None, dest="b_mm",
                        help=f"chamber width, mm (default 1.8; {box('b_mm')})")
    parser.add_argument("--h-mm", type=float, default=None, dest="h_mm",
                        help=f"chamber height, mm (default 0.15; {box('h_mm')})")
    parser.add_argument("--W-mm", type=float, default=None, dest="W_mm",
                        help="actuator width, mm (default 3; the emulator answers every "
                             "scaled copy of its box: the same ratios to W)")
    parser.add_argument("--body-length-mm", type=float, default=None, dest="body_length_mm",
                        help="body length, mm (default 12, or L + 2 if longer, at W = 3; "
                             "scaled with W)")
    parser.add_argument("--chamber-offset-mm", type=float, default=None,
                        dest="chamber_offset_mm",
                        help="clamped end to chamber start, mm (default: centred)")
    # the flag names of `balloon solve`; --body and --membrane are kept as aliases
    parser.add_argument("--body-material", "--body", default=None, dest="body_material",
                        help="body material id (default pdms_1_10)")
    parser.add_argument("--membrane-material", "--membrane", default=None,
                        dest="membrane_material",
                        help="membrane material id (default ecoflex_00_30)")
    from solver.design_space import REDUCED_RATIO_RANGE

    ratio = ("the emulator answers any S whose ratio body S / membrane S is "
             f"{REDUCED_RATIO_RANGE[0]:g}..{REDUCED_RATIO_RANGE[1]:g}")
    parser.add_argument("--body-stiffness-scale", type=float, default=None, metavar="S",
                        help=f"body mu = S x the preset's ({ratio}: only the ratio shapes "
                             "the curve, a common S scales the pressure axis)")
    parser.add_argument("--membrane-stiffness-scale", type=float, default=None, metavar="S",
                        help=f"membrane mu = S x the preset's ({ratio})")
    attach_design_ranges(parser)   # a word that is not a number is told the range


def add_model_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", default="emulator", metavar="NAME|PATH",
                        help="emulator (default), exponential, paper, a saved calibrated "
                             "model's name, or a model file")
    parser.add_argument("--models-dir", type=Path, default=None,
                        help="where saved calibrated models are (default: BALLOON_MODELS_DIR,"
                             " else ~/.balloon/models)")
    parser.add_argument("--form", choices=("exponential", "extended"), default=None,
                        help="model form (default: each family's fitted default)")
    allowed_action(parser.add_argument("--level", type=float, default=0.95,
                                       help="band level (0.95)"), ASKED_LEVEL_WORDS)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def check_level(level: float) -> None:
    """InputError naming --level unless a request could ask for it (ASKED_LEVELS)."""
    from solver.errors import InputError

    if not ASKED_LEVELS[0] <= level <= ASKED_LEVELS[1]:
        raise InputError("--level", f"got {level:g}", ASKED_LEVEL_WORDS)


def add_pump_arguments(parser: argparse.ArgumentParser) -> None:
    allowed_action(parser.add_argument("--flow-ul-s", type=float, default=None, metavar="UL_S",
                                       help="the syringe pump's flow rate, ul/s (adds the "
                                            "time axis)"), FLOW_RANGE)
    parser.add_argument("--inlet", action="store_true",
                        help="add the pump-gauge pressure, chamber + R Q (Hagen-Poiseuille; "
                             "default the paper's channel 0.5 x 3 x 0.15 mm, water)")
    allowed_action(parser.add_argument("--channel-mm", type=float, nargs=3,
                                       metavar=("W", "L", "H"), help="inlet channel width, "
                                       "length, height, mm (with --inlet)"),
                   _inlet_range(W="channel_width_mm", L="channel_length_mm",
                                H="channel_height_mm"))
    allowed_action(parser.add_argument("--tubing-mm", type=float, nargs=2,
                                       metavar=("LENGTH", "BORE"),
                                       help="tubing length and bore, mm (with --inlet)"),
                   _inlet_range(LENGTH="tubing_length_mm", BORE="tubing_bore_mm"))
    allowed_action(parser.add_argument("--viscosity-pa-s", type=float, default=None,
                                       help="the fluid's viscosity, Pa s (with --inlet; "
                                            "default water, 1e-3)"),
                   _inlet_range(unit="Pa s", viscosity="viscosity_pa_s"))


def _inlet_range(unit: str = "mm", **names: str) -> str:
    """An inlet option's values' ranges in words, from the Inlet's one table
    (``surrogate.hydraulics.LIMITS``): ``"LENGTH 0 to 100000, BORE 0.05 to 20 mm"``."""
    return ", ".join(f"{word} {INLET_LIMITS[name][0]:g} to {INLET_LIMITS[name][1]:g}"
                     for word, name in names.items()) + f" {unit}"


# the request fields of service/pump.py -> the flags that set them
PUMP_FLAGS = {"pressures_pa": "--pressures", "volumes_ul": "--volumes", "times_s": "--times",
              "angles_deg": "--angles-deg",
              "flow_ul_s": "--flow-ul-s", "pressures_at": "--pressures-at",
              "inlet.channel_width_mm": "--channel-mm", "inlet.channel_length_mm": "--channel-mm",
              "inlet.channel_height_mm": "--channel-mm", "inlet.tubing_length_mm": "--tubing-mm",
              "inlet.tubing_bore_mm": "--tubing-mm", "inlet.viscosity_pa_s": "--viscosity-pa-s",
              "level": "--level", "angle_deg": "--angles-deg"}
# a design's fields -> the options that set them (those of `balloon solve` too)
DESIGN_FLAGS = {name: "--" + name.replace("_", "-") for name in (
    "L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "W_mm", "body_length_mm", "chamber_offset_mm",
    "body_material", "membrane_material")}


def as_flag(exc: Exception) -> Exception:
    """An InputError naming a request or design field, renamed to the CLI option that
    sets it (``t_mm`` -> ``--t-mm``; a refusal outside the box renames every field it
    names)."""
    from solver.design_space import OutOfBoxError

    names = {**PUMP_FLAGS, **DESIGN_FLAGS}
    if isinstance(exc, OutOfBoxError):
        return exc.renamed(names)
    # the request fields its words name are the CLI's options too ("allowed: pressures_pa"
    # for a model that answers by pressure only is --pressures here)
    return renamed_as_options(exc, names, PUMP_FLAGS)


def _as_flags(text: str | None, flags: dict[str, str] = PUMP_FLAGS) -> str | None:
    """``text`` with each request field it names (``flags``' keys, ``PUMP_FLAGS`` by
    default; those with a unit in their name, not a word such as "level") as its CLI
    option."""
    if not text:
        return text
    fields = "|".join(re.escape(f) for f in flags if "_" in f)
    return re.sub(rf"(?<![\w.-])({fields})(?![\w.])", lambda m: flags[m.group(1)], text)


def renamed_as_options(exc: Exception, flags: dict[str, str],
                       words: dict[str, str] | None = None) -> Exception:
    """An InputError whose field is one of ``flags``' keys as the CLI option that sets
    it, and the fields its words name (``words``' keys, ``flags``' by default) too
    ("leave pressure_pa out" is "leave --pressure-pa out" on the command line); any
    other exception as it is."""
    from solver.errors import InputError

    if isinstance(exc, InputError) and exc.field in flags:
        words = flags if words is None else words
        return InputError(flags[exc.field], _as_flags(exc.detail, words),
                          _as_flags(exc.allowed, words), allowed_said=exc.allowed_said)
    return exc


def inlet_from_args(args: argparse.Namespace) -> object:
    """``surrogate.hydraulics.Inlet`` of --inlet (None without it)."""
    from solver.errors import InputError
    from surrogate.hydraulics import Inlet

    given = [f for f, v in (("--channel-mm", args.channel_mm), ("--tubing-mm", args.tubing_mm),
                            ("--viscosity-pa-s", args.viscosity_pa_s)) if v is not None]
    if not args.inlet:
        if given:
            raise InputError(given[0], "describes the inlet", "with --inlet")
        return None
    kw: dict[str, float] = {}
    if args.channel_mm:
        kw.update(zip(("channel_width_mm", "channel_length_mm", "channel_height_mm"),
                      args.channel_mm, strict=True))
    if args.tubing_mm:
        kw.update(tubing_length_mm=args.tubing_mm[0], tubing_bore_mm=args.tubing_mm[1])
    if args.viscosity_pa_s is not None:
        kw["viscosity_pa_s"] = args.viscosity_pa_s
    try:
        return Inlet(**kw)
    except InputError as exc:
        raise as_flag(exc) from None


def design_from_args(args: argparse.Namespace) -> object:
    from solver.design import design_from_dict
    from solver.design_space import REDUCED_RATIO_RANGE, named_material, scaled_material
    from solver.errors import InputError
    from solver.materials import MATERIALS

    data: dict[str, object] = {k: getattr(args, k) for k in (
        "L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "W_mm", "body_length_mm", "chamber_offset_mm")
                               if getattr(args, k, None) is not None}
    for layer, default in (("body", "pdms_1_10"), ("membrane", "ecoflex_00_30")):
        preset = getattr(args, f"{layer}_material", None) or default
        scale = getattr(args, f"{layer}_stiffness_scale", None)
        if scale is None:
            data[f"{layer}_material"] = preset
            continue
        lo, hi = STIFFNESS_SCALE_LIMITS
        if not lo <= scale <= hi:
            raise InputError(f"--{layer}-stiffness-scale", f"got {scale:g}",
                             f"{lo:g} <= S <= {hi:g} (the emulator's box: body S / "
                             f"membrane S {REDUCED_RATIO_RANGE[0]:g}.."
                             f"{REDUCED_RATIO_RANGE[1]:g})")
        if preset not in MATERIALS:    # a scaled id (pdms_1_10*2) would be scaled twice
            try:
                scaled = named_material(preset) is not None
            except InputError:         # a preset's id with a scale no material has (x0)
                scaled = True
            said = (f"{preset!r} is already scaled: --{layer}-stiffness-scale {scale:g} "
                    "would scale it twice" if scaled else f"unknown material {preset!r}")
            raise InputError(f"--{layer}-material", said,
                             f"a preset ({', '.join(sorted(MATERIALS))}) with "
                             f"--{layer}-stiffness-scale, or <preset>*<scale> alone")
        data[f"{layer}_material"] = scaled_material(preset, scale)
    return design_from_dict(data)


def saved_model_name(spec: str | None) -> str | None:
    """``spec`` if it names a saved calibrated model: a bare name (not "paper", not a path
    or a .json file)."""
    from surrogate.calibration._saved import NAME_PATTERN

    if (spec is None or spec == "paper" or spec.endswith(".json") or Path(spec).exists()
            or not NAME_PATTERN.fullmatch(spec)):
        return None
    return spec


def surrogate_from_args(args: argparse.Namespace) -> object:
    """The model named by --model: the service's own names first, then a file path."""
    from service.models import BUILT_IN_MODELS, ModelRegistry
    from service.settings import get_settings
    from solver.errors import InputError, NotFoundError
    from surrogate import open_surrogate

    allowed = (", ".join(BUILT_IN_MODELS) + ", a saved calibrated model's name, or an "
               "existing model file (.json)")
    if args.model is not None and not args.model.strip():   # never read as the default
        raise InputError("--model", f"{args.model!r} names no model", allowed)
    spec = args.model or "emulator"
    if Path(spec).suffix == ".json" or "/" in spec or os.sep in spec:   # a file's path
        path = Path(spec)
        if not path.is_file():
            what = ("is a directory" if path.is_dir() else "is not a regular file (a device "
                    "or a pipe)" if path.exists() else "file not found")
            raise InputError("--model", f"{spec}: {what}", allowed)
        return open_model_file(Path(spec), getattr(args, "form", None))
    settings = get_settings()
    models_dir = getattr(args, "models_dir", None) or settings.models_dir
    registry = ModelRegistry(settings.surrogate_path, models_dir, settings.emulator_path)
    if spec in ("fitted", "exponential"):
        registry.load_exponential()     # the emulator loads only when asked (get)
    try:
        model = registry.get(spec) if spec != "paper" else open_surrogate("paper")
    except NotFoundError as exc:
        raise InputError("--model", str(exc), allowed) from None
    form = getattr(args, "form", None)
    if form is not None and hasattr(model, "with_form"):
        model = model.with_form(form)
    return model


def open_model_file(path: Path, form: str | None) -> object:
    """An emulator or exponential-model JSON file, told apart by its ``format``."""
    from surrogate import open_surrogate
    from surrogate.emulator import load_emulator

    with path.open("rb") as file:      # its head only (the file may be large)
        head = file.read(200).decode("utf-8", errors="replace")
    if '"balloon-emulator"' in head:
        return load_emulator(path)
    return open_surrogate(str(path)).with_form(form)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("predict", help="predict bending angles from the surrogate",
                                   description=__doc__.split("\n\n")[0].replace("``", ""))
    add_design_arguments(parser)
    group = parser.add_mutually_exclusive_group(required=True)
    add_number_list(group, "--pressures", "PA", "pressures, Pa", AXES["pressures_pa"])
    allowed_action(group.add_argument("--pressure-range", type=float, nargs=3,
                                      metavar=("START", "STOP", "NUM"),
                                      help="NUM evenly spaced pressures from START to STOP, Pa"),
                   _RANGE_ALLOWED)
    add_number_list(group, "--volumes", "UL", "injected volumes, ul (the emulator)",
                    AXES["volumes_ul"])
    add_number_list(group, "--times", "S", "times since the pump started, s (with --flow-ul-s)",
                    AXES["times_s"])
    add_pump_arguments(parser)
    parser.add_argument("--pressures-at", choices=("chamber", "pump_gauge"), default="chamber",
                        help="where --pressures were read (pump_gauge: with --inlet and "
                             "--flow-ul-s)")
    add_model_arguments(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from service.pump import PumpQuestion, predict_answer
    from solver.errors import InputError

    check_level(args.level)
    try:
        design = design_from_args(args)
    except InputError as exc:
        raise as_flag(exc) from None
    inlet = inlet_from_args(args)
    s = surrogate_from_args(args)
    pressures = args.pressures
    if args.pressure_range is not None:
        start, stop, num = args.pressure_range
        lo, hi, _ = AXES["pressures_pa"]   # checked before linspace (inf: a warning)
        if (not 1 <= num <= MAX_ASKED_VALUES or num != int(num)
                or not all(math.isfinite(x) and lo <= x <= hi for x in (start, stop))):
            raise InputError("--pressure-range", f"START = {start:g}, STOP = {stop:g}, "
                             f"NUM = {num:g}", _RANGE_ALLOWED)
        pressures = np.linspace(start, stop, int(num)).tolist()
    question = PumpQuestion(pressures, args.volumes, args.times, args.flow_ul_s, inlet,  # type: ignore[arg-type]
                            args.pressures_at)
    try:
        body = predict_answer(s, design, question, args.model or "emulator", args.level)
    except InputError as exc:
        raise as_flag(exc) from None
    if args.json:
        print(json.dumps(body, indent=1))
        return 0
    print(f"model {body['model']} ({body['form'] or 'calibrated'}), L = {design.L_mm:g} mm, "  # type: ignore
          f"t = {design.t_mm:g} mm, band {100 * args.level:g} %"  # type: ignore
          + (f", {body['flow_ul_s']:g} ul/s" if body.get("flow_ul_s") else "")
          + (f", inlet R = {body['inlet']['resistance_pa_per_ul_s']:.1f} Pa per ul/s"
             if body.get("inlet") else ""))
    columns = [c for c in ("time_s", "volume_ul", "pressure_pa", "pump_pressure_pa",
                           "angle_deg", "lower_deg", "upper_deg", "force_mn",
                           "force_lower_mn", "force_upper_mn")
               if body.get(c) is not None]
    print(" ".join(f"{c:>14s}" for c in columns))
    for i in range(len(body["angle_deg"])):
        print(" ".join(_cell(body[c][i]) for c in columns))
    print("pressure_pa is the chamber's" + (", pump_pressure_pa the pump gauge's (+ R Q)"
                                           if body.get("inlet") else ""))
    print_validity(body["validity"])
    return 0


def _cell(value: float | None) -> str:
    return f"{'--':>14s}" if value is None else f"{value:z14.3f}"


def print_validity(validity: dict) -> None:
    if validity["in_domain"] and not validity.get("flags"):
        print("validity: inside the fitted domain")
    else:
        print("validity: " + ", ".join(validity["flags"]))
        for m in validity["messages"]:
            print(f"  - {m}")
