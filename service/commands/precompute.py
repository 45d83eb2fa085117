"""``balloon precompute GRID.toml --db curves.h5``: solve every grid design missing from
the database (process pool of ``--workers``, or a Dask cluster with ``--scheduler``).

The grid is validated completely before any solve. Each finished solve is written at
once; Ctrl-C, SIGTERM or a killed job keeps every finished record, and the same command
resumes.
The exact command, the grid's text and the versions are recorded in the file's metadata.

Exit codes (docs/database.md): 0 done; 1 solves lost to worker errors, or finished
results parked (the database could not be written, or another writer held it); 2 refused
before any solve (a bad grid or option, a damaged database, the database being filled by
another job or held by another writer); 130 / 143 stopped by Ctrl-C / SIGTERM.
"""

from __future__ import annotations

import argparse
import shlex
import signal
import sys
from pathlib import Path

from service.commands.numbers import checked_int, int_action
from surrogate.emulator.adaptive import ADAPTIVE_COUNTS

WORKERS = (1, 256)   # local worker processes, lo <= N <= hi


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "precompute", help="fill a curve database from a grid file",
        description="Solve every design of GRID that the database does not hold yet "
                    "(see docs/database.md for the grid format).")
    parser.add_argument("grid", metavar="GRID.toml", help="grid file (TOML)")
    parser.add_argument("--db", required=True, metavar="PATH",
                        help="curve database (HDF5); created if missing")
    int_action(parser.add_argument("--workers", type=int, default=1, metavar="N",
                                   help="local worker processes (default 1)"), "N", *WORKERS)
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="run on a Dask cluster, e.g. tcp://host:8786 (extra 'cluster')")
    parser.add_argument("--retry-failed", action="store_true",
                        help="solve again the designs stored as failed")
    int_action(parser.add_argument(
        "--adaptive", type=int, default=None, metavar="N",
        help="instead of the grid's designs, solve the N designs where the emulator "
             "(--emulator, default: fitted from --db) is least certain; the grid file "
             "still gives the settings"), "N", *ADAPTIVE_COUNTS)
    parser.add_argument("--emulator", default=None, metavar="PATH",
                        help="emulator file for --adaptive (default: fit one from --db)")
    parser.add_argument("--designs-from", default=None, metavar="PATH",
                        help="instead of the grid's designs, every design of this curve "
                             "database, each with its record's settings (tip, spring) and "
                             "the grid's [settings] on top: the database rebuilt on new "
                             "settings, e.g. another mesh")
    parser.add_argument("--dry-run", action="store_true",
                        help="validate the grid and report what would be solved")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


def command_line(args: argparse.Namespace) -> str:
    """The command that reproduces this run (recorded in the database)."""
    words = ["balloon", "precompute", args.grid, "--db", args.db]
    if args.scheduler:
        words += ["--scheduler", args.scheduler]
    else:
        words += ["--workers", str(args.workers)]
    if args.retry_failed:
        words.append("--retry-failed")
    if getattr(args, "adaptive", None):
        words += ["--adaptive", str(args.adaptive)]
        if args.emulator:
            words += ["--emulator", args.emulator]
    if getattr(args, "designs_from", None):
        words += ["--designs-from", args.designs_from]
    return shlex.join(words)


def _adaptive_grid(grid: object, args: argparse.Namespace) -> object:
    """The grid with its points replaced by the N most uncertain designs."""
    from dataclasses import replace

    from solver.errors import InputError
    from solver.store import CurveStore
    from surrogate.emulator import fit_emulator, load_emulator
    from surrogate.emulator.adaptive import next_designs

    if args.emulator:
        try:
            emulator = load_emulator(args.emulator)
        except InputError as exc:   # the file itself (too large, a pipe): named by option
            if exc.field != "model":
                raise
            raise InputError("--emulator", exc.detail, exc.allowed) from None
    else:
        if not Path(args.db).is_file():
            raise InputError("--adaptive", f"{args.db} does not exist yet",
                             "a database with curves to fit the emulator from")
        with CurveStore(args.db) as db:
            emulator = fit_emulator(list(db.records()))
    points = next_designs(emulator, args.adaptive, grid.settings)  # type: ignore[attr-defined]
    print(f"--adaptive {args.adaptive}: {len(points)} designs where the emulator is least "
          "certain", file=sys.stderr)
    return replace(grid, points=tuple(points))  # type: ignore[type-var]


def _designs_from_grid(grid: object, args: argparse.Namespace) -> tuple[object, dict]:
    """The grid with its points replaced by the designs of the database ``--designs-from``
    (in the order they were stored), each with its record's settings and the settings the
    grid's [settings] table names on top; and the source's
    provenance (its generating command, grid and runs), recorded in the new file as
    ``designs_from``."""
    import tomllib
    from dataclasses import fields, replace

    from solver.errors import InputError
    from solver.precompute.grid import GridPoint
    from solver.settings import SolverSettings
    from solver.store import CurveStore, record_key

    source = Path(args.designs_from)
    if not source.is_file():
        raise InputError("--designs-from", f"{args.designs_from} is not a file",
                         "the path of a curve database (HDF5)")
    if source.resolve() == Path(args.db).resolve():
        raise InputError("--designs-from", "is the database being filled (--db)",
                         "another curve database")
    # the settings the grid's [settings] table names, whether or not they are defaults
    # (a grid that asks for the default mesh must move records of another mesh to it)
    named = tomllib.loads(grid.text).get("settings", {})  # type: ignore[attr-defined]
    own = {f.name: getattr(grid.settings, f.name)  # type: ignore[attr-defined]
           for f in fields(SolverSettings) if f.name in named}
    try:
        with CurveStore(source) as db:
            records = sorted(db.records(),
                             key=lambda r: (str(r.provenance.get("created_utc", "")), r.key))
            meta = db.metadata
    except InputError as e:        # not HDF5, not a curve database: named as this option
        raise InputError("--designs-from", e.detail, e.allowed) from None
    points, seen = [], set()
    for rec in records:
        settings = replace(rec.settings, **own).validated()
        key = record_key(rec.design, settings)
        if key not in seen:
            seen.add(key)
            points.append(GridPoint(key=key, design=rec.design, settings=settings))
    print(f"--designs-from {args.designs_from}: {len(points)} designs, with "
          f"{', '.join(f'{k} = {v!r}' for k, v in own.items()) or 'their own settings'}",
          file=sys.stderr)
    origin = {"path": args.designs_from, "n_records": len(records),
              **{k: meta[k] for k in ("generator_command", "grid_toml", "runs") if k in meta}}
    return replace(grid, points=tuple(points)), origin  # type: ignore[type-var]


def _interrupt(signum: int, frame: object) -> None:
    """SIGTERM (``kill PID``) raised as Ctrl-C's KeyboardInterrupt: the job stops the
    same way (workers stopped, finished records kept)."""
    raise KeyboardInterrupt


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from solver.errors import InputError
    from solver.precompute import load_grid, plan, precompute
    from solver.precompute.job import refuse_damaged
    from solver.store import CurveStore, StoreBusyError

    checked_int("--workers", args.workers, "N", *WORKERS)
    db_path = Path(args.db)
    if db_path.exists() and not db_path.is_file():
        raise InputError("--db", f"{args.db} is not a file", "the path of an HDF5 file")
    if not db_path.parent.is_dir():
        raise InputError("--db", f"directory {str(db_path.parent)!r} does not exist",
                         "a path in an existing directory")
    if args.adaptive is not None:   # before the grid, the database and any fit
        from surrogate.emulator.adaptive import check_count

        check_count(args.adaptive)
    grid = load_grid(args.grid)
    if args.adaptive is not None and args.designs_from:
        raise InputError("--designs-from", "given with --adaptive",
                         "one source of designs: --adaptive N or --designs-from PATH")
    if args.adaptive is not None:
        grid = _adaptive_grid(grid, args)
    origin = None
    if args.designs_from:
        grid, origin = _designs_from_grid(grid, args)
    if args.dry_run:
        statuses: dict[str, str] = {}
        if Path(args.db).exists():
            with CurveStore(args.db) as db:
                refuse_damaged(db)
                statuses = db.statuses()
        todo, summary = plan(grid.points, statuses, args.retry_failed)
        print(f"{grid.source}: {len(grid)} designs; in {args.db}: {summary.skipped_done} "
              f"done, {summary.skipped_failed} failed (skipped); would solve {len(todo)}")
        return 0
    # `kill PID` (SIGTERM) stops the job like Ctrl-C: workers stopped, finished records kept
    terminated: list[int] = []   # SIGTERM's number once it came: exit 143, Ctrl-C's 130

    def on_sigterm(signum: int, frame: object) -> None:
        terminated.append(signum)
        _interrupt(signum, frame)

    previous = signal.signal(signal.SIGTERM, on_sigterm)
    try:
        summary = precompute(grid, args.db, workers=args.workers, scheduler=args.scheduler,
                             retry_failed=args.retry_failed, progress=not args.no_progress,
                             command=command_line(args),
                             metadata=None if origin is None else {"designs_from": origin})
    except StoreBusyError as exc:  # another job, or a writer past the wait: nothing solved
        raise InputError("--db", str(exc)) from None
    finally:
        signal.signal(signal.SIGTERM, previous)
    for line in summary.lines():
        print(line, file=sys.stderr)
    if summary.write_error or summary.parked:  # the lines above say where and why
        return 1
    if summary.interrupted:
        return 128 + (terminated[0] if terminated else signal.SIGINT)  # the shell's way
    return 1 if summary.errors else 0
