"""The ``balloon`` command: one subcommand per task.

Each subcommand lives in ``service/commands/<name>.py`` and exposes
``register(subparsers)``, which adds its parser and sets ``func`` to a function
``run(args) -> int``. User mistakes (``BalloonError``, bad files) print one line
on stderr and exit 2; nothing prints a traceback for them.
"""

from __future__ import annotations

import argparse
import re
import sys
from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import NoReturn

from solver.errors import BalloonError, InputError, NotFoundError

# Subcommands in the order `balloon --help` lists them.
COMMAND_MODULES = (
    "service.commands.solve",
    "service.commands.serve",
    "service.commands.precompute",
    "service.commands.db",
    "service.commands.fit",
    "service.commands.predict",
    "service.commands.inverse",
    "service.commands.calibrate",
)


def package_version() -> str:
    try:
        return version("balloon-actuator")
    except PackageNotFoundError:
        return "0+unknown"


class Parser(argparse.ArgumentParser):
    """argparse with its usage errors on one line, like every other error of the
    command: ``balloon predict: error: MESSAGE (see `balloon predict --help`)``.
    Subcommand parsers are of the same class (argparse's default)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {self._with_range(message)} "
                     f"(see `{self.prog} --help`)\n")

    def _with_range(self, message: str) -> str:
        """argparse's "argument --L-mm: invalid float value: 'abc'" with the option's
        allowed range, when the option carries one (service.commands.numbers)."""
        match = re.fullmatch(r"argument (\S+): invalid (?:float|int) value: (.*)", message)
        if match is None:
            return message
        for action in self._actions:
            allowed = getattr(action, "allowed", None)
            if allowed and "/".join(action.option_strings) == match[1]:
                return f"argument {match[1]}: {match[2]} is not a number (allowed: {allowed})"
        return message


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="balloon",
        description="Design bending balloon actuators: FE solves, curve database, "
                    "surrogate fits, inverse design and the REST service.")
    parser.add_argument("--version", action="version", version=f"balloon {package_version()}")
    subparsers = parser.add_subparsers(title="commands", metavar="COMMAND")
    for name in COMMAND_MODULES:
        import_module(name).register(subparsers)
    return parser


def _error(what: object) -> None:
    """One line on stderr, whatever the message holds: a control character from the
    user's own input (a CR of a CR-only file, an escape) is shown escaped, not obeyed."""
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(what))
    print(f"balloon: error: {text}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except (InputError, NotFoundError) as exc:
        _error(exc)
        return 2
    except (FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        # the file as the user named it and why, without Python's "[Errno 2]"
        what = f"{exc.filename}: {exc.strerror}" if exc.filename and exc.strerror else exc
        _error(what)
        return 2
    except BalloonError as exc:
        _error(exc)
        return 1
    except KeyboardInterrupt:
        print("balloon: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # Output piped into a reader that stopped early (e.g. `| head`): not an error.
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:
        # a write the system refused after the checks (a full disk): one line, no trace
        what = (f"{exc.filename}: {exc.strerror}" if exc.filename and exc.strerror
                else exc.strerror or type(exc).__name__)
        _error(what)
        return 1


if __name__ == "__main__":
    sys.exit(main())
