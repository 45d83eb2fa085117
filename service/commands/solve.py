"""``balloon solve``: one finite-element solve of a design, with outputs to files."""

from __future__ import annotations

import argparse
import json
import sys

from service.commands.numbers import allowed_action, attach_design_ranges, attach_setting_ranges
from solver.curve import Curve
from solver.design import design_from_dict
from solver.io import CSV_COLUMNS
from solver.materials import MATERIALS
from solver.settings import (
    CONTROLS,
    ELEMENTS,
    MAX_MESH_LEVEL,
    MESH_DIVISIONS,
    TIPS,
    SolverSettings,
    range_words,
)

# the settings' fields -> the options that set them (an error names what the user typed)
SETTING_FLAGS = {"mesh_level": "--mesh", "mesh_divisions": "--mesh-divisions",
                 "element": "--element", "control": "--control",
                 "max_angle_deg": "--max-angle-deg", "max_pressure_pa": "--max-pressure-pa",
                 "flow_ul_s": "--flow-ul-s", "bulk_ratio": "--bulk-ratio", "tip": "--tip",
                 "spring_k_n_per_m": "--spring-k-n-per-m"}


def _mm(what: str) -> str:
    """A length option's help; its range is LIMITS_MM's, said by the parser's formatter
    (service.commands.numbers.help_with_allowed)."""
    return f"{what}, mm (default %(default)s)"


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "solve", help="solve one design with the FE solver (pressure-angle curve)",
        description="Inflate one actuator design with the 3D finite-element solver and "
                    "write its pressure-volume-angle curve. Lengths in mm, pressures in Pa, "
                    "angles in degrees, volumes in ul (= mm^3).")
    g = p.add_argument_group("design (defaults: the paper's standard design, Table 3)")
    g.add_argument("--L-mm", type=float, default=7.1, help=_mm("chamber length"))
    g.add_argument("--t-mm", type=float, default=0.5,
                   help=_mm("membrane thickness"))
    g.add_argument("--T-mm", type=float, default=1.0,
                   help=_mm("body thickness above the chamber"))
    g.add_argument("--b-mm", type=float, default=1.8, help=_mm("chamber width"))
    g.add_argument("--h-mm", type=float, default=0.15, help=_mm("chamber height"))
    g.add_argument("--W-mm", type=float, default=3.0, help=_mm("actuator width"))
    g.add_argument("--body-length-mm", type=float, default=None,
                   help=_mm("body length").replace(
                       "default %(default)s", "default max(12, L + 2) at W = 3, scaled with W"))
    g.add_argument("--chamber-offset-mm", type=float, default=None,
                   help=_mm("clamped end to chamber start").replace(
                       "default %(default)s", "default: centred"))
    materials = ", ".join(sorted(MATERIALS))
    g.add_argument("--body-material", default="pdms_1_10",
                   help=f"body (layer A) material: {materials} (default %(default)s)")
    g.add_argument("--membrane-material", default="ecoflex_00_30",
                   help=f"membrane (layer B) material: {materials} (default %(default)s)")
    attach_design_ranges(p)   # a word that is not a number is told the range
    s = p.add_argument_group("solver")
    d = SolverSettings()
    s.add_argument("--control", choices=CONTROLS, default=d.control,
                   help="volume: inject volume, pressure follows (passes pressure maxima); "
                        "pressure: prescribe pressure (default %(default)s)")
    s.add_argument("--element", choices=ELEMENTS, default=d.element,
                   help="hex2: 27-node triquadratic; hex1: 8-node trilinear, faster "
                        "(default %(default)s)")
    allowed_action(s.add_argument(
        "--mesh", type=int, default=d.mesh_level, metavar="LEVEL",
        help=f"mesh level 0 to {MAX_MESH_LEVEL}: level n has n + 1 times the divisions of "
             "level 0 (default %(default)s)"), range_words("mesh_level"))
    s.add_argument("--mesh-divisions", choices=MESH_DIVISIONS, default=d.mesh_divisions,
                   help="level-0 resolution: balanced (the database's: end walls graded "
                        "to the chamber, two chamber layers; within 2 %% in angle), former "
                        "(the default before it, 2.3-2.9 %% low in angle) or fine_x (twice "
                        "the former's divisions along x, ~2x the time; default "
                        "%(default)s)")
    s.add_argument("--max-angle-deg", type=float, default=d.max_angle_deg,
                   help="stop at this bending angle, degrees (default %(default)s)")
    s.add_argument("--max-pressure-pa", type=float, default=d.max_pressure_pa,
                   help="stop at this cavity pressure, Pa (default %(default)s)")
    s.add_argument("--flow-ul-s", type=float, default=d.flow_ul_s,
                   help="injection rate for the reported time = volume / flow, ul/s "
                        "(default %(default)s)")
    s.add_argument("--bulk-ratio", type=float, default=d.bulk_ratio,
                   help="bulk modulus over initial shear modulus K / mu0, dimensionless "
                        "(default %(default)s)")
    s.add_argument("--tip", choices=TIPS, default=d.tip,
                   help="free tip, a linear spring on the tip (--spring-k-n-per-m), or "
                        "blocked (default %(default)s)")
    s.add_argument("--spring-k-n-per-m", type=float, default=d.spring_k_n_per_m,
                   help="tip spring stiffness for --tip spring, N/m (> 0 for a spring; "
                        "default %(default)s)")
    o = p.add_argument_group("output (files are checked before the solve)")
    o.add_argument("--json", metavar="PATH", help="write design, settings and curve as JSON")
    o.add_argument("--csv", metavar="PATH",
                   help="write the curve as CSV (columns: " + ", ".join(CSV_COLUMNS) + ")")
    o.add_argument("--plot", metavar="PATH", help="write a PNG of angle and volume vs pressure")
    o.add_argument("--vtk", metavar="PATH",
                   help="write the final deformed state with stretch and stress (VTU)")
    o.add_argument("--quiet", action="store_true", help="no progress bar")
    attach_setting_ranges(p)
    p.set_defaults(func=run)


def _design(args: argparse.Namespace):
    return design_from_dict({
        "L_mm": args.L_mm, "t_mm": args.t_mm, "T_mm": args.T_mm, "b_mm": args.b_mm,
        "h_mm": args.h_mm, "W_mm": args.W_mm, "body_length_mm": args.body_length_mm,
        "chamber_offset_mm": args.chamber_offset_mm, "body_material": args.body_material,
        "membrane_material": args.membrane_material})


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse output paths that cannot be written before spending minutes on a solve."""
    from service.commands.outputs import (
        PLOT_SUFFIXES,
        VTK_SUFFIXES,
        check_output,
        distinct_outputs,
    )

    outputs = (("json", None), ("csv", None), ("plot", PLOT_SUFFIXES), ("vtk", VTK_SUFFIXES))
    for option, suffixes in outputs:
        check_output(getattr(args, option), f"--{option}", suffixes)
    distinct_outputs(tuple((f"--{option}", getattr(args, option)) for option, _ in outputs))


def _settings(args: argparse.Namespace) -> SolverSettings:
    return SolverSettings(
        mesh_level=args.mesh, mesh_divisions=args.mesh_divisions, element=args.element,
        control=args.control,
        max_angle_deg=args.max_angle_deg, max_pressure_pa=args.max_pressure_pa,
        flow_ul_s=args.flow_ul_s, bulk_ratio=args.bulk_ratio, tip=args.tip,
        spring_k_n_per_m=args.spring_k_n_per_m).validated()


def progress_bar(settings: SolverSettings, quiet: bool) -> tuple[object, object]:
    """(tqdm bar, on_step) for a solve: a free tip's bending in degrees up to the stop
    angle; a held tip (spring, blocked), which bends little or not at all, as the share
    of the way to the first of the stops it does reach (pressure, injected volume, the
    angle too), in per cent."""
    from tqdm import tqdm

    if settings.tip == "free":
        bar = tqdm(total=round(settings.max_angle_deg), unit="deg", disable=quiet,
                   file=sys.stderr, desc="bending")
    else:
        bar = tqdm(total=100, unit="%", disable=quiet, file=sys.stderr,
                   desc=f"{settings.tip} tip")

    def on_step(info: dict) -> None:
        if settings.tip == "free":
            done = abs(info["angle_deg"])
        else:
            done = 100 * max(info["pressure_pa"] / settings.max_pressure_pa,
                             info["volume_ul"] / settings.max_volume_ul,
                             abs(info["angle_deg"]) / settings.max_angle_deg)
        bar.n = min(round(done), bar.total)
        bar.set_postfix(p_pa=f"{info['pressure_pa']:.0f}", step=info["step"],
                        **({"cutbacks": info["cutbacks"]} if info.get("cutbacks") else {}))
        bar.refresh()

    return bar, on_step


def run(args: argparse.Namespace) -> int:
    from service.commands.predict import DESIGN_FLAGS
    from solver.atomic_file import atomic_output
    from solver.errors import InputError
    from solver.io import curve_to_csv, plot_curve
    from solver.stepping import inflate

    _check_outputs(args)
    try:
        design, settings = _design(args), _settings(args)
    except InputError as exc:     # name the option the user typed, not the field
        names = {**DESIGN_FLAGS, **SETTING_FLAGS}
        raise InputError(names.get(exc.field, exc.field), exc.detail, exc.allowed) from None
    bar, on_step = progress_bar(settings, args.quiet)
    curve, model, u = inflate(design, settings, on_step=on_step)
    bar.close()  # type: ignore[attr-defined]
    print(f"{curve.status}: {curve.reason}; {len(curve)} points, {curve.n_dofs} dofs, "
          f"{curve.wall_time_s:.1f} s")
    for note in curve.stability_notes():
        print(f"stability: {note}")
    print(table(curve, with_force=settings.tip != "free"))
    # each output whole or not at all (a full disk leaves the former file in place)
    if args.json:
        from surrogate.json_plain import plain_json

        with atomic_output(args.json) as tmp, open(tmp, "w") as fh:  # strict JSON: a free
            json.dump(plain_json({"design": design.as_dict(),         # tip's NaN force is
                                  "settings": settings.as_dict(),     # null
                                  "curve": curve.as_dict()}), fh, indent=1, allow_nan=False)
    if args.csv:
        with atomic_output(args.csv) as tmp:
            curve_to_csv(curve, str(tmp))
    if args.plot:
        with atomic_output(args.plot, keep_suffix=True) as tmp:
            plot_curve(curve, str(tmp), title=f"L = {design.L_mm} mm, t = {design.t_mm} mm")
    if args.vtk:
        from solver.export import write_vtu

        with atomic_output(args.vtk, keep_suffix=True) as tmp:
            write_vtu(str(tmp), model, u)
    return 0 if curve.status != "failed" else 1


def table(c: Curve, with_force: bool) -> str:
    """The curve as the printed table: pressure (Pa), injected volume (ul), time (s),
    angle (deg), the membrane's largest stretch and, for a held tip (``with_force``), the
    tip's reaction force (mN), the quantity a blocked run exists for."""
    rows = [f"{'pressure_pa':>12} {'volume_ul':>10} {'time_s':>8} {'angle_deg':>10} "
            f"{'stretch':>8}" + (f" {'force_mn':>10}" if with_force else "")]
    for i in range(len(c)):
        # "z": a value that rounds to zero is printed 0.00, never -0.00
        rows.append(f"{c.pressure_pa[i]:z12.1f} {c.volume_ul[i]:z10.3f} {c.time_s[i]:z8.2f} "
                    f"{c.angle_deg[i]:z10.2f} {c.max_membrane_stretch[i]:8.3f}"
                    + (f" {c.force_mn[i]:z10.4f}" if with_force else ""))
    return "\n".join(rows)
