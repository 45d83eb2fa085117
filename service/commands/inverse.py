"""``balloon inverse``: pressures for target angles of one design, or designs for a target.

    balloon inverse --L-mm 7.1 --t-mm 0.5 --angles-deg 10 45       # one design: pressures
    balloon inverse --L-mm 7.1 --t-mm 0.5 --angles-deg 45 --flow-ul-s 2.5   # + volume, time
    balloon inverse --angle-deg 45 --pressure-pa 1500               # designs: 45 deg there
    balloon inverse --kind pressure_budget --angle-deg 45 --pressure-pa 1500   # within a budget
    balloon inverse --kind angle_at_pressure --angle-deg 30 --pressure-pa 1200 \\
        --L-range 4 12 --t-range 0.5 1 --pair pdms_1_10/ecoflex_00_30 --objective compact
    balloon inverse --kind force_at_pressure --force-mn 0.5 --pressure-pa 1500
    balloon inverse --angle-deg 45 --volume-ul 20                   # a pump: 45 deg at 20 ul
    balloon inverse --kind volume_budget --angle-deg 45 --volume-ul 20   # with <= 20 ul
    balloon inverse --angle-deg 45 --time-s 8 --flow-ul-s 2.5       # after 8 s at 2.5 ul/s
    balloon inverse --kind time_budget --angle-deg 45 --time-s 8 --flow-ul-s 2.5
    balloon inverse --designs designs.csv --angles-deg 45 -o ranked.csv   # many designs

Targets, objectives and defaults: docs/surrogate.md (``surrogate.search.design_search``: the
same search as POST /v1/inverse).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import replace

from service.commands.numbers import (
    allowed_action,
    checked_int,
    int_action,
    number_action,
    range_text,
)
from service.commands.predict import (
    add_design_arguments,
    add_model_arguments,
    add_number_list,
    add_pump_arguments,
    as_flag,
    check_level,
    design_from_args,
    inlet_from_args,
    print_validity,
    renamed_as_options,
    surrogate_from_args,
)
from service.pump import MAX_ANGLE_DEG
from solver.errors import InputError
from surrogate.predictor import FE_PRESSURE_STOP_PA, FE_VOLUME_STOP_UL
from surrogate.search.design_search import N_RESULTS_MAX
from surrogate.search.design_target import DEFAULT_KIND, KINDS, MAX_TARGET, OBJECTIVES
from surrogate.volume_control import MAX_TIME_S

N_RESULTS = (1, N_RESULTS_MAX)   # designs a search lists, lo <= n <= hi

# The search's bounds (surrogate.search.design_search.SearchBounds field -> flag, what it bounds);
# a pinned range (LO = HI) fixes that variable (one mould: --L-range 10 10). Each range
# lies within the emulator's box (search_box); the stiffness scales default to 1 1.
RANGE_FLAGS = {
    "L_mm": ("--L-range", "chamber length bounds"),
    "t_mm": ("--t-range", "membrane thickness bounds"),
    "T_mm": ("--T-range", "body thickness bounds"),
    "b_mm": ("--b-range", "chamber width bounds"),
    "h_mm": ("--h-range", "chamber height bounds"),
    "body_stiffness_scale": ("--body-stiffness-range", "body mu / preset mu bounds"),
    "membrane_stiffness_scale": ("--membrane-stiffness-range", "membrane mu / preset mu bounds"),
}
# a design search's request fields -> the options that set them (a refusal names these)
SEARCH_FLAGS = {**{name: flag for name, (flag, _) in RANGE_FLAGS.items()},
                "material_pairs": "--pair", "angle_deg": "--angle-deg",
                "force_mn": "--force-mn", "pressure_pa": "--pressure-pa",
                "objective": "--objective", "volume_ul": "--volume-ul", "time_s": "--time-s",
                "flow_ul_s": "--flow-ul-s", "kind": "--kind", "level": "--level"}


def search_box(name: str) -> tuple[float, float, str]:
    """(low, high, unit) of a searched variable in the emulator's box: a length in mm
    (solver.design_space.BOX_MM) or a layer's stiffness scale (STIFFNESS_SCALE_RANGE)."""
    from solver.design_space import BOX_MM, STIFFNESS_SCALE_RANGE

    if name in BOX_MM:
        return (*BOX_MM[name], "mm")
    return (*STIFFNESS_SCALE_RANGE, "")


def _range_help(name: str, what: str) -> str:
    lo, hi, unit = search_box(name)
    default = "the box" if unit else "1 1: as sold"
    return f"{what}, within {range_text(lo, hi, unit)} (the emulator's box; default {default})"


def check_in_box(flag: str, name: str, bounds: list[float] | None) -> None:
    """Refuse bounds that reach past the emulator's box: the search would be clipped to it
    without saying so, and a user asking for 2..30 mm would read an answer for 4..18 as
    one for 2..30. InputError naming ``flag`` and the box's range."""
    if bounds is None:
        return
    lo, hi, unit = search_box(name)
    low, high = bounds
    if not lo <= low <= high <= hi:  # NaN fails every comparison: refused too
        raise InputError(flag, f"got {low:g} {high:g}",
                         f"LO <= HI within {lo:g}..{hi:g} {unit}".rstrip()
                         + ", the emulator's box; LO = HI pins it")


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "inverse", help="pressure for an angle, or designs that meet a target",
        description=__doc__.split("\n\n")[0].replace("``", ""),
        formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__.split("\n\n")[1])
    add_design_arguments(parser, required=False)
    add_number_list(parser, "--angles-deg", "DEG",
                    "one design (--L-mm, --t-mm): the pressures for these angles",
                    (-MAX_ANGLE_DEG, MAX_ANGLE_DEG, "deg"))
    parser.add_argument("--kind", choices=KINDS, default=None,
                        help=f"design target (default {DEFAULT_KIND}; force_at_pressure "
                             "with --force-mn, angle_at_volume with --volume-ul, "
                             "angle_at_time with --time-s)")
    allowed_action(parser.add_argument("--angle-deg", type=float, help="target angle, deg: "
                                       "positive bends away from the membrane, negative "
                                       "towards it (the reversed pair)"),
                   f"0 < |angle| <= {MAX_TARGET['angle_deg']:g} deg")
    allowed_action(parser.add_argument("--force-mn", type=float, help="target blocked-tip "
                                       "force, mN (signed as the angle)"),
                   f"0 < |force| <= {MAX_TARGET['force_mn']:g} mN")
    allowed_action(parser.add_argument("--pressure-pa", type=float,
                                       help="target pressure or budget, Pa"),
                   f"0 < pressure <= {FE_PRESSURE_STOP_PA:g} Pa, the FE's pressure stop (a "
                   f"budget: <= {MAX_TARGET['pressure_pa']:g} Pa)")
    allowed_action(parser.add_argument("--volume-ul", type=float, help="a pump's target: "
                                       "injected volume or budget, ul (0 < V <= "
                                       f"{FE_VOLUME_STOP_UL:g}, the FE's volume stop)"),
                   f"0 < volume <= {FE_VOLUME_STOP_UL:g} ul")
    allowed_action(parser.add_argument("--time-s", type=float, help="a pump's target: time "
                                       "or budget at --flow-ul-s from the undeformed state, s "
                                       "(volume = flow x time)"),
                   f"0 < time <= {MAX_TIME_S:g} s")
    for name, (flag, what) in RANGE_FLAGS.items():
        lo, hi, unit = search_box(name)
        number_action(parser.add_argument(flag, type=float, nargs=2, metavar=("LO", "HI"),
                                          help=_range_help(name, what)), lo, hi, unit)
    parser.add_argument("--pair", action="append", metavar="BODY/MEMBRANE",
                        help="allowed material pair (repeatable; default: every family)")
    parser.add_argument("--objective", choices=OBJECTIVES,
                        help="ranking (default: pressure for pressure_budget, volume for "
                             "volume_budget and time_budget, certainty otherwise)")
    int_action(parser.add_argument("-n", "--n-results", type=int,
                                   help="designs to list (default 5)"),
               "n", *N_RESULTS, "designs")
    add_pump_arguments(parser)  # with --angles-deg: the volume, time and pump-gauge pressure;
    # a design search reads --flow-ul-s with --time-s
    add_model_arguments(parser)
    parser.add_argument("--designs", metavar="CSV",
                        help="many designs, one per row of a CSV file (columns L_mm, t_mm "
                             "and any of T_mm, b_mm, h_mm, W_mm, body_material, "
                             "membrane_material, body_stiffness_scale, "
                             "membrane_stiffness_scale, and your own): the pressures for "
                             "--angles-deg of each, as CSV with the model's identity; a "
                             "row the model refuses keeps its place with its error")
    parser.add_argument("-o", "--output", metavar="CSV",
                        help="with --designs: write the CSV here (default: standard "
                             "output; progress goes to standard error)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_level(args.level)
    if args.output is not None and args.designs is None:
        raise InputError("-o", "writes the CSV of --designs", "leave -o out, or give --designs")
    table = _check_many(args) if args.designs is not None else None  # before the model loads
    if args.n_results is not None:      # before the model is loaded (seconds)
        checked_int("-n", args.n_results, "n", *N_RESULTS, "designs")
    s = surrogate_from_args(args)
    if not hasattr(s, "inverse"):
        raise InputError("--model", f"the saved calibrated model {args.model!r} predicts but "
                         "does not invert (a calibration against an exponential model)",
                         "paper, a surrogate file, a calibration against the emulator, or "
                         "leave --model out")
    if table is not None:
        return _many_designs(s, args, *table)
    if args.angles_deg is not None:
        if args.L_mm is None or args.t_mm is None:
            raise InputError("--angles-deg", "needs the design's --L-mm and --t-mm")
        return _one_design(s, args)
    if not (hasattr(s, "evaluate_designs") or hasattr(s, "covered_slices")):
        # as POST /v1/inverse: a saved calibrated model answers one design at a time
        raise InputError("--model", f"model {args.model!r} does not answer a design search "
                         "(a saved calibrated model answers one design at a time: give "
                         "--L-mm, --t-mm and --angles-deg for the pressure of an angle)",
                         "emulator, exponential, paper, or a model file")
    return _design_search(s, args)


#: a design search's own options, by argparse dest, which one design's answer does not read
SEARCH_ONLY = {"kind": "--kind", "angle_deg": "--angle-deg", "force_mn": "--force-mn",
               "pressure_pa": "--pressure-pa", "volume_ul": "--volume-ul",
               "time_s": "--time-s", "pair": "--pair", "objective": "--objective",
               "n_results": "-n", **{flag[2:].replace("-", "_"): flag
                                     for flag, _ in RANGE_FLAGS.values()}}


#: one design's own flags, by argparse dest: a designs file's rows give them instead
DESIGN_DESTS = ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "W_mm", "body_length_mm",
                "chamber_offset_mm", "body_material", "membrane_material",
                "body_stiffness_scale", "membrane_stiffness_scale")


def _check_many(args: argparse.Namespace) -> tuple[list[str], list[dict[str, str]]]:
    """--designs' file read and its companions checked before the model loads (seconds):
    --angles-deg given, no design flag (the rows give the designs), no design search's
    option, -o writable. The file's (header, rows)."""
    from pathlib import Path

    from service.commands.batch import read_designs
    from service.commands.outputs import check_output

    if args.angles_deg is None:
        raise InputError("--designs", "needs --angles-deg: the pressures for these angles "
                         "of each design", "--designs FILE --angles-deg DEG [DEG ...]")
    if args.json:
        raise InputError("--json", "--designs writes CSV (one row per design and angle)",
                         "leave --json out; the single design's answer (--L-mm, --t-mm) "
                         "prints JSON")
    for dest in DESIGN_DESTS:
        if getattr(args, dest, None) is not None:
            flag = "--" + dest.replace("_", "-")
            raise InputError(flag, "sets one design; with --designs each row gives its own",
                             f"a {dest} column in the designs file, or leave --designs out")
    for dest, flag in SEARCH_ONLY.items():
        if getattr(args, dest, None) is not None:
            raise InputError(flag, "sets a design search's target or bounds; --designs "
                             "answers --angles-deg for each row", f"leave {flag} out")
    check_output(args.output, "-o", (".csv",), inputs=(("--designs", Path(args.designs)),))
    return read_designs(Path(args.designs))


def _many_designs(s: object, args: argparse.Namespace, header: list[str],
                  rows: list[dict[str, str]]) -> int:
    """--designs: the pressures for --angles-deg of every row's design, as CSV (one row
    per design and angle), the model loaded once (service.commands.batch)."""
    from service.commands.batch import model_identity, run_batch
    from service.pump import inverse_answer
    from solver.atomic_file import atomic_output

    inlet = inlet_from_args(args)
    columns = ("angle_deg", "pressure_pa", "lower_pa", "upper_pa",
               *(("pump_pressure_pa",) if inlet is not None else ()),
               "volume_ul", "volume_lower_ul", "volume_upper_ul",
               *(("time_s", "time_lower_s", "time_upper_s") if args.flow_ul_s else ()),
               "in_domain", "flags")

    def answer(design: object):
        # a refusal names the row's column (L_mm), not the one design's flag (--L-mm)
        body = inverse_answer(s, design, args.angles_deg, args.model or "emulator",
                              args.level, args.flow_ul_s, inlet)  # type: ignore[arg-type]
        for i in range(len(body["angle_deg"])):
            yield {**{c: (body.get(c) or [None] * (i + 1))[i] for c in columns[:-2]},
                   "in_domain": body["validity"]["in_domain"],
                   "flags": body["validity"]["flags"]}

    identity = model_identity(args.model, getattr(args, "models_dir", None))
    if args.output is None:
        refused = run_batch(header, rows, columns, answer, identity, sys.stdout)
    else:
        with atomic_output(args.output) as tmp, tmp.open("w", newline="") as out:
            refused = run_batch(header, rows, columns, answer, identity, out)
    print(f"balloon: {len(rows) - refused} of {len(rows)} designs answered"
          + (f"; {refused} refused (their error column says why)" if refused else "")
          + (f", written to {args.output}" if args.output else ""), file=sys.stderr)
    return 0 if refused < len(rows) else 2


def _one_design(s: object, args: argparse.Namespace) -> int:
    from service.pump import inverse_answer

    for dest, flag in SEARCH_ONLY.items():  # given, never silently dropped
        if getattr(args, dest, None) is not None:
            raise InputError(flag, "sets a design search's target or bounds; the pressures "
                             "for --angles-deg of one design do not read it",
                             f"leave {flag} out, or --angles-deg out for a design search")
    design = design_from_args(args)
    try:
        body = inverse_answer(s, design, args.angles_deg, args.model or "emulator", args.level,
                              args.flow_ul_s, inlet_from_args(args))  # type: ignore[arg-type]
    except InputError as exc:
        raise as_flag(exc) from None
    if args.json:
        print(json.dumps(body, indent=1))
        return 0
    print(f"model {body['model']}, L = {design.L_mm:g} mm, t = "  # type: ignore[attr-defined]
          f"{design.t_mm:g} mm, band {100 * body['level']:g} %"  # type: ignore[attr-defined]
          + (f", {body['flow_ul_s']:g} ul/s" if body.get("flow_ul_s") else ""))
    columns = [c for c in ("angle_deg", "pressure_pa", "lower_pa", "upper_pa",
                           "pump_pressure_pa", "volume_ul", "volume_lower_ul",
                           "volume_upper_ul", "time_s", "time_lower_s", "time_upper_s")
               if body.get(c) is not None]
    print(" ".join(f"{c:>12s}" for c in columns))
    for i in range(len(body["angle_deg"])):
        print(" ".join("--".rjust(12) if body[c][i] is None else f"{body[c][i]:z12.2f}"
                       for c in columns))
    print_validity(body["validity"])
    return 0


def _design_search(s: object, args: argparse.Namespace) -> int:
    """Designs for a target over the box: the same search as POST /v1/inverse."""
    from service.convert import jsonable
    from surrogate import DesignTarget
    from surrogate.search.design_search import SearchBounds, search_designs

    # one design's flags (--L-mm for L_mm, ...) do not steer the search: refused, naming
    # what does (the range flags, RANGE_FLAGS, for the variables it searches)
    others = {"body_material": "--pair BODY/MEMBRANE",
              "membrane_material": "--pair BODY/MEMBRANE",
              "W_mm": "the search's W = 3 mm (scale its designs' lengths by W / 3)",
              "body_length_mm": "the default body length",
              "chamber_offset_mm": "the centred chamber"}
    instead = {**{dest: f"{flag} LO HI (LO = HI pins it)"
                  for dest, (flag, _) in RANGE_FLAGS.items()}, **others}
    for dest, allowed in instead.items():
        if getattr(args, dest, None) is not None:
            raise InputError("--" + dest.replace("_", "-"), "sets one design (with "
                             "--angles-deg); a design search does not read it", allowed)
    if args.inlet or args.channel_mm or args.tubing_mm or args.viscosity_pa_s is not None:
        raise InputError("--inlet", "the pump-gauge pressure is given for one design (with "
                         "--angles-deg); a design search does not read the inlet",
                         "leave out --inlet, --channel-mm, --tubing-mm, --viscosity-pa-s")
    kind = args.kind or ("force_at_pressure" if args.force_mn is not None
                         else "angle_at_time" if args.time_s is not None
                         else "angle_at_volume" if args.volume_ul is not None
                         else DEFAULT_KIND)
    pairs: tuple[tuple[str, str], ...] | None = None
    if args.pair:
        found = []
        for text in args.pair:
            body, sep, membrane = text.partition("/")
            if not sep:
                raise InputError("--pair", f"got {text!r}", "BODY/MEMBRANE material ids")
            found.append((body, membrane))
        pairs = tuple(found)
    if args.n_results is None:    # a given one was checked before the model was loaded
        args.n_results = 5
    try:
        target = DesignTarget(kind, args.pressure_pa, angle_deg=args.angle_deg,
                              force_mn=args.force_mn, volume_ul=args.volume_ul,
                              time_s=args.time_s, flow_ul_s=args.flow_ul_s)
    except InputError as exc:
        raise renamed_as_options(exc, SEARCH_FLAGS) from None
    ranges = {name: (tuple(v) if (v := getattr(args, flag[2:].replace("-", "_"))) else None)
              for name, (flag, _) in RANGE_FLAGS.items()}
    for name, (flag, _) in RANGE_FLAGS.items():
        check_in_box(flag, name, ranges[name])  # type: ignore[arg-type]
    try:
        res = search_designs(s, target, SearchBounds(**ranges, pairs=pairs),
                             objective=args.objective, n_results=args.n_results,
                             level=args.level)
    except InputError as exc:
        raise renamed_as_options(exc, SEARCH_FLAGS) from None
    res = replace(res, model=args.model or "emulator")
    if args.json:   # JSON has no NaN: a quantity a pump's target has none of is null
        print(json.dumps(jsonable(res.as_dict()), indent=1, allow_nan=False))
        return 0 if res.feasible else 1
    print(f"model {res.model}: {kind}, objective {res.objective}: {res.explanation}")
    if not res.feasible:
        return 1
    if target.by_volume:
        _print_pump_candidates(res, target)
        return 0
    unit = "mN" if kind == "force_at_pressure" else "deg"
    print(f"{'rank':>4s} {'L_mm':>7s} {'t_mm':>6s} {'T_mm':>6s} {'b_mm':>6s} {'h_mm':>6s} "
          f"{'body/membrane':36s} {'score':>9s} "
          f"{'p_need_pa':>10s} {'p_band_pa':>16s} {'at_p_' + unit:>8s} {'band':>16s} flags")
    for c in res.candidates:
        flags = ",".join(c.curve.validity["flags"]) or "-"
        d = c.design
        materials = f"{d.body_material.id}/{d.membrane_material.id}"
        print(f"{c.rank:4d} {d.L_mm:7.3f} {d.t_mm:6.3f} {d.T_mm:6.3f} {d.b_mm:6.3f} "
              f"{d.h_mm:6.3f} {materials:36s} {c.score:9.3g} "
              + (f"{c.pressure_needed_pa:10.1f} {c.pressure_lower_pa:7.0f}.."
                 f"{c.pressure_upper_pa:<7.0f} " if math.isfinite(c.pressure_needed_pa)
                 else f"{'--':>10s} {'--':>16s} ")
              + (f"{c.value_at_pressure:z8.2f} {c.value_lower:z7.2f}.."
                 f"{c.value_upper:<z7.2f} " if math.isfinite(c.value_at_pressure)
                 else f"{'--':>8s} {'--':>16s} ")
              + flags)
    _print_score_and_tolerances(res, unit)
    return 0


def _print_score_and_tolerances(res: object, unit: str) -> None:
    """What the score means, and what a mould's tolerance does to each answer."""
    from surrogate.search.ranking import SCORE_MEANING

    objective = res.objective  # type: ignore[attr-defined]
    print(f"score ({objective}): {SCORE_MEANING.get(objective, 'lower ranks first')}")
    for c in res.candidates:  # type: ignore[attr-defined]
        if c.change_per_0_01_mm:
            changes = ", ".join(f"{n.removesuffix('_mm')} {v:+.3g}"
                                for n, v in c.change_per_0_01_mm.items())
            print(f"rank {c.rank}, each length 0.01 mm larger: {changes} {unit}")


def _print_pump_candidates(res: object, target: object) -> None:
    """The table of a pump's target: the volume (and time) needed with its band, and at
    the target volume the angle with its band and the chamber pressure."""
    timed = target.time_s is not None  # type: ignore[attr-defined]

    def band(x: float | None, lo: float | None, hi: float | None, width: int) -> str:
        if x is None:
            return f"{'--':>{width}s} {'--':>15s}"
        return f"{x:z{width}.2f} {lo:z7.2f}..{hi:<z6.2f}"

    print(f"{'rank':>4s} {'L_mm':>7s} {'t_mm':>6s} {'T_mm':>6s} {'b_mm':>6s} {'h_mm':>6s} "
          f"{'body/membrane':36s} {'score':>9s} {'v_need_ul':>9s} {'v_band_ul':>15s} "
          + (f"{'t_need_s':>8s} {'t_band_s':>15s} " if timed else "")
          + f"{'at_v_deg':>8s} {'band':>15s} {'p_at_v_pa':>9s} flags")
    for c in res.candidates:  # type: ignore[attr-defined]
        d = c.design
        materials = f"{d.body_material.id}/{d.membrane_material.id}"
        p = c.pressure_at_volume_pa
        print(f"{c.rank:4d} {d.L_mm:7.3f} {d.t_mm:6.3f} {d.T_mm:6.3f} {d.b_mm:6.3f} "
              f"{d.h_mm:6.3f} {materials:36s} {c.score:9.3g} "
              + band(c.volume_needed_ul, c.volume_lower_ul, c.volume_upper_ul, 9) + " "
              + (band(c.time_needed_s, c.time_lower_s, c.time_upper_s, 8) + " "
                 if timed else "")
              + band(c.angle_at_volume_deg, c.angle_at_volume_lower_deg,
                     c.angle_at_volume_upper_deg, 8) + " "
              + (f"{p:9.0f} " if p is not None else f"{'--':>9s} ")
              + (",".join(c.curve.validity["flags"]) or "-"))
    # a budget's design is read where it meets the angle (mould_tolerance.change_per_tolerance)
    where = ("the volume it needs" if target.budget  # type: ignore[attr-defined]
             else f"{target.at:.4g} ul")  # type: ignore[attr-defined]
    _print_score_and_tolerances(res, f"deg at {where}")
