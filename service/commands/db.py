"""``balloon db ls|show|export|seal|salvage``: look into a curve database.

    balloon db ls curves.h5 [--status failed] [--where L_mm=7.1 ...] [--json]
    balloon db show curves.h5 [KEY] [--json]      # no KEY: the file's metadata
    balloon db export curves.h5 [KEY ...] --format csv|json [-o OUT] [--where ...]
    balloon db seal curves.h5                     # write a file of older code sealed
    balloon db salvage curves.h5 -o new.h5        # the intact records of a damaged file

Keys may be abbreviated to any unique prefix. CSV is long format: one row per
curve point, with the record's key, status and design (lengths in mm, material ids) on
every row; NaN is written as ``nan``. JSON is a list of full records (``Record.as_dict``),
NaN as null.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from typing import Any

from solver.curve import STATUSES as CURVE_STATUSES
from solver.io import CSV_COLUMNS
from surrogate.json_plain import plain_json as jsonable  # NaN and inf as null

CSV_DESIGN = ("L_mm", "t_mm", "T_mm", "b_mm", "h_mm", "W_mm", "body_length_mm",
              "chamber_offset_mm", "body_material", "membrane_material")
# the curve columns of `balloon solve --csv` (one name per column everywhere:
# tip_dx_mm, tip_dz_mm are the two columns of the Curve's tip_displacement_mm array)
CSV_CURVE = CSV_COLUMNS


# the record filters of ``db ls`` and ``db export``, said once
STATUS_HELP = ("only the records that ended so: complete (reached a stop: 90 deg, the volume "
               "or pressure stop), stopped (ended early by a limit such as max_steps), failed "
               "(a step could not converge)")
WHERE_HELP = ("only the records whose design, settings or status field has this value, e.g. "
              "L_mm=7.1 or tip=blocked (several, or --where again: all of them)")

def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("db", help="list, show, export, seal and salvage curve "
                                   "database records",
                                   description="List, show and export the records of a curve "
                                               "database, seal it, or salvage its intact "
                                               "records (docs/database.md).")
    sub = parser.add_subparsers(title="db commands", metavar="ACTION", required=True)
    ls = sub.add_parser("ls", help="list the records")
    ls.add_argument("db", help="curve database (HDF5)")
    ls.add_argument("--status", choices=CURVE_STATUSES, help=STATUS_HELP)
    ls.add_argument("--where", nargs="+", action="extend", default=[], metavar="FIELD=VALUE",
                    help=WHERE_HELP)
    ls.add_argument("--json", action="store_true", help="JSON lines instead of a table")
    ls.set_defaults(func=run_ls)
    show = sub.add_parser("show", help="show one record, or the file's metadata")
    show.add_argument("db", help="curve database (HDF5)")
    show.add_argument("key", nargs="?", help="record key (a unique prefix is enough)")
    show.add_argument("--json", action="store_true", help="the full record as JSON")
    show.set_defaults(func=run_show)
    export = sub.add_parser("export", help="export curves to CSV or JSON")
    export.add_argument("db", help="curve database (HDF5)")
    export.add_argument("keys", nargs="*", metavar="KEY", help="records (default: all)")
    export.add_argument("--format", choices=("csv", "json"), default="csv",
                        help="csv (default): one row per step; json: the whole records")
    export.add_argument("--where", nargs="+", action="extend", default=[], metavar="FIELD=VALUE",
                        help=WHERE_HELP)
    export.add_argument("--status", choices=CURVE_STATUSES, help=STATUS_HELP)
    export.add_argument("-o", "--output", default="-", help="output file (default stdout)")
    export.set_defaults(func=run_export)
    seal = sub.add_parser("seal", help="check the file and write it sealed (its checksum "
                          "in the header, checked by every reader)",
                          description="Check the file (a guarded full read when it has no "
                                      "seal) and publish it again with the seal that "
                                      "readers check before HDF5 parses it, and the "
                                      "summary index that lists its records at once "
                                      "(files written by this version have both).")
    seal.add_argument("db", help="curve database (HDF5)")
    seal.set_defaults(func=run_seal)
    salvage = sub.add_parser("salvage", help="copy the intact records of a damaged "
                             "database to a new file",
                             description="Copy every record that reads back (its checksum "
                                         "and key intact) into a new curve database, with "
                                         "the file's metadata; name the damaged ones. "
                                         "`balloon precompute` on the new file solves "
                                         "their designs again.")
    salvage.add_argument("db", help="curve database (HDF5)")
    salvage.add_argument("-o", "--output", required=True, metavar="NEW.h5",
                         help="the new database (must not exist)")
    salvage.set_defaults(func=run_salvage)


def query_filters(args: argparse.Namespace) -> dict[str, object]:
    """The records' filter from ``--where FIELD=VALUE ...`` and ``--status``, each checked
    before the database is opened (``solver.store.hdf5.check_filter``) and refused naming
    the option as typed (``--where L_mm``, not the store's ``L_mm``); a field given twice,
    or a status by both options, is refused rather than read as its last value."""
    from solver.errors import InputError
    from solver.number_text import ascii_float, ascii_int
    from solver.store.hdf5 import check_filter

    filters: dict[str, object] = {}
    for item in args.where:
        name, sep, text = item.partition("=")
        if not sep or not name:
            raise InputError("--where", f"got {item!r}", "FIELD=VALUE, e.g. L_mm=7.1")
        option = f"--where {name}"
        if name in filters:
            raise InputError(option, "given twice", "each field once")
        value: object = text    # a number only as the command line writes numbers
        for read in (ascii_int, ascii_float):
            try:
                value = read(text)
                break
            except ValueError:
                continue
        try:
            check_filter(name, value)
        except InputError as exc:
            raise InputError(option, exc.detail, exc.allowed) from None
        filters[name] = value
    if args.status:
        if "status" in filters:
            raise InputError("--status", "given with --where status=... too", "one of them")
        filters["status"] = args.status
    return filters


def resolve(db: Any, prefix: str) -> str:
    from solver.errors import InputError, NotFoundError

    matches = [k for k in db.keys() if k.startswith(prefix)]
    if not matches:
        raise NotFoundError(f"no record with a key starting {prefix!r} in {db.path}")
    if len(matches) > 1:
        raise InputError("key", f"{prefix!r} matches {len(matches)} records",
                         "a longer prefix")
    return matches[0]


def selected(db: Any, args: argparse.Namespace) -> list[Any]:
    filters = query_filters(args)
    if getattr(args, "keys", None):
        records = [db.get(resolve(db, k)) for k in args.keys]
        if filters:
            wanted = {r.key for r in db.query(**filters)}
            records = [r for r in records if r.key in wanted]
        return records
    return db.query(**filters) if filters else list(db.records())


def run_ls(args: argparse.Namespace) -> int:
    from solver.store import CurveStore

    filters = query_filters(args)
    with CurveStore(args.db) as db:
        rows = db.summaries(**filters)
    rows.sort(key=lambda r: (r["design"]["body_material"], r["design"]["membrane_material"],
                             r["design"]["L_mm"], r["design"]["t_mm"], r["key"]))
    if args.json:
        for row in rows:
            print(json.dumps(jsonable(row), sort_keys=True))
        return 0
    print(f"{'key':12}  {'status':8}  {'L_mm':>6}  {'t_mm':>5}  {'T_mm':>5}  "
          f"{'body/membrane':28}  {'mesh':6}  {'steps':>5}  {'wall_s':>7}")
    for row in rows:
        d, s = row["design"], row["settings"]
        print(f"{row['key'][:12]:12}  {row['status']:8}  {d['L_mm']:6.2f}  {d['t_mm']:5.2f}  "
              f"{d['T_mm']:5.2f}  {d['body_material'] + '/' + d['membrane_material']:28}  "
              f"{str(s['mesh_level']) + ' ' + s['element']:6}  {row['n_steps']:5d}  "
              f"{float(row['provenance'].get('wall_time_s', 0.0)):7.1f}")
    print(f"{len(rows)} records{none_met(db, filters) if not rows else ''}", file=sys.stderr)
    return 0


def none_met(db: Any, filters: dict[str, object]) -> str:
    """Words on each filter that no record of ``db`` meets by itself, with what the records
    hold: "; no record has body_material 'garbage' (the records hold: ecoflex_00_30,
    pdms_1_10, pdms_1_15 and 1849 scaled ids, <preset>*<scale>)", or a number's range --
    a custom id may be any word, so a misspelt one is a filter that meets nothing, not an
    error. "" when each filter alone meets some record. A value longer than an error
    line shows whole is cut, as there (``service.cli.shown``: a material of 5000
    characters was echoed whole)."""
    from service.cli import shown
    from solver.store.hdf5 import summary_field

    words = []
    for name, value in filters.items():
        if db.summaries(**{name: value}):
            continue
        held = {summary_field(row, name) for row in db.summaries()}
        numbers = sorted(v for v in held if isinstance(v, int | float))
        texts = sorted(str(v) for v in held if not isinstance(v, int | float))
        plain = [v for v in texts if "*" not in v]
        span = ([] if not numbers else [f"{numbers[0]:g}"] if len(numbers) == 1 else
                [f"from {numbers[0]:g} to {numbers[-1]:g} ({len(numbers)} values)"])
        parts = span + plain
        if len(texts) > len(plain):
            parts.append(f"{len(texts) - len(plain)} scaled ids, <preset>*<scale>")
        words.append(f"; no record has {name} {value!r} (the records hold: "
                     f"{', '.join(parts) or 'nothing'})")
    return shown("".join(words))


def run_seal(args: argparse.Namespace) -> int:
    from pathlib import Path

    from service.commands.interrupts import interrupts_kept
    from solver.store import CurveStore
    from solver.store.locking import no_database

    if not Path(args.db).is_file():  # writing mode would create an empty database
        raise no_database(args.db, ": nothing to seal")
    # a Ctrl-C that landed in an h5py callback during the seal stops here, at the latest,
    # not after "sealed" is printed (its redelivery from a thread may come later)
    with interrupts_kept(), CurveStore(args.db, mode="a") as db:
        db.seal()
        n = len(db)
    print(f"{args.db}: sealed ({n} records)", file=sys.stderr)
    return 0


def run_salvage(args: argparse.Namespace) -> int:
    from service.commands.outputs import check_output
    from solver.store.salvage import salvage

    check_output(args.output, "--output", inputs=(("the database", args.db),))
    result = salvage(args.db, args.output)
    for line in result.lines():
        print(line, file=sys.stderr)
    return 0


def run_show(args: argparse.Namespace) -> int:
    from solver.store import CurveStore

    with CurveStore(args.db) as db:
        if args.key is None:
            print(json.dumps(jsonable(db.metadata), indent=2, sort_keys=True))
            return 0
        record = db.get(resolve(db, args.key))
    if args.json:
        print(json.dumps(jsonable(record.as_dict()), indent=2))
        return 0
    c = record.curve
    print(f"key         {record.key}")
    print(f"status      {c.status}: {c.reason}")
    for name, value in record.design.as_dict().items():
        if isinstance(value, dict):
            value = f"{value['id']} (Ogden mu_kpa={value['mu_kpa']}, alpha={value['alpha']})"
        print(f"design      {name} = {value}")
    print("settings    " + ", ".join(f"{k}={v}" for k, v in record.settings.as_dict().items()))
    print("provenance  " + ", ".join(f"{k}={v}" for k, v in record.provenance.items()))
    if len(c):
        print(f"curve       {len(c)} points, {c.n_dofs} dofs; last: {c.pressure_pa[-1]:.1f} Pa, "
              f"{c.volume_ul[-1]:.3f} ul, {c.angle_deg[-1]:.2f} deg")
    else:
        print("curve       no points")
    return 0


def curve_rows(record: Any) -> list[list[object]]:
    c = record.curve
    d = record.design
    design = [d.L_mm, d.t_mm, d.T_mm, d.b_mm, d.h_mm, d.W_mm, d.body_length_mm,
              d.chamber_offset_mm, d.body_material.id, d.membrane_material.id]
    rows = []
    for i in range(len(c)):
        rows.append([record.key, c.status, *design, c.pressure_pa[i], c.volume_ul[i],
                     c.time_s[i], c.angle_deg[i], c.tip_displacement_mm[i, 0],
                     c.tip_displacement_mm[i, 1], c.max_membrane_stretch[i], c.force_mn[i],
                     int(c.newton_iterations[i]), c.residual_norm[i],
                     int(c.negative_eigenvalues[i])])
    return rows


def run_export(args: argparse.Namespace) -> int:
    from service.commands.outputs import check_output
    from solver.store import CurveStore

    check_output(args.output, "--output", inputs=(("the database", args.db),))
    with CurveStore(args.db) as db:
        records = selected(db, args)
        hint = none_met(db, query_filters(args)) if not records else ""
    if args.output == "-":
        _export(records, args.format, sys.stdout)
    else:   # a full disk leaves the former file, not half of the new one
        from solver.atomic_file import atomic_output

        with atomic_output(args.output) as tmp, open(tmp, "w", newline="",
                                                     encoding="utf-8") as out:
            _export(records, args.format, out)
    print(f"exported {len(records)} records{hint}", file=sys.stderr)
    return 0


def _export(records: list[Any], form: str, out: Any) -> None:
    """The records as JSON or CSV (one row per curve point) on the text stream ``out``."""
    if form == "json":
        json.dump([jsonable(r.as_dict()) for r in records], out, indent=1)
        out.write("\n")
    else:
        writer = csv.writer(out)
        writer.writerow(["key", "status", *CSV_DESIGN, *CSV_CURVE])
        for record in records:
            writer.writerows(curve_rows(record))
