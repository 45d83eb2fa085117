"""The ``balloon`` command: one subcommand per task.

Each subcommand lives in ``service/commands/<name>.py`` and exposes
``register(subparsers)``, which adds its parser and sets ``func`` to a function
``run(args) -> int``. User mistakes (``BalloonError``, bad files) print one line
on stderr and exit 2; nothing prints a traceback for them.
"""

from __future__ import annotations

import argparse
import functools
import re
import sys
from importlib import import_module
from importlib.metadata import PackageNotFoundError, version
from typing import NoReturn

from service.commands.interrupts import caused_by_interrupt, interrupts_kept
from service.commands.numbers import help_with_allowed
from solver.errors import BalloonError, InputError, NotFoundError
from solver.number_text import (
    INTEGER_FORM,
    NEGATIVE_NUMBER,
    NUMBER_FORM,
    WrittenNumber,
    ascii_float,
    ascii_int,
    is_integer_text,
    unheld_words,
)
from solver.plain_text import escaped

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
    Subcommand parsers are of the same class (argparse's default). A ``float`` or
    ``int`` option reads its word by the service's one rule for numbers written as text
    (``solver.number_text``: ASCII decimal digits; ``1_000`` and ``١٠٠٠`` are refused, as
    a query parameter refuses them)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self._negative_number_matcher = NEGATIVE_NUMBER    # -1e3 a value, as -5 is
        self.register("type", float, held_float)
        self.register("type", int, held_int)
        self.register("action", None, StoreOnce)       # argparse's default action
        self.register("action", "store", StoreOnce)

    def parse_known_args(self, args=None, namespace=None):  # type: ignore[override]
        parsed, rest = super().parse_known_args(args, namespace)
        parsed.__dict__.pop(StoreOnce.GIVEN, None)    # StoreOnce's record, not an option
        return parsed, rest

    def _get_formatter(self) -> argparse.HelpFormatter:
        """The parser's formatter, each option's help stating its allowed range
        (``service.commands.numbers.help_with_allowed``)."""
        return _stating_ranges(self.formatter_class)(prog=self.prog)

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {shown(self._with_range(message))} "
                     f"(see `{self.prog} --help`)\n")

    def _with_range(self, message: str) -> str:
        """argparse's "argument --L-mm: invalid float value: 'abc'" as "'abc' is not a
        number", with the form numbers are written in and the option's allowed range when
        it carries one (service.commands.numbers)."""
        listed = re.fullmatch(r"argument (\S+): (.* is not a list of numbers \(.*)\)", message)
        if listed is not None:   # a list option's word (service.commands.predict.number_list)
            allowed = self._allowed(listed[1])
            return message if allowed is None else f"{message[:-1]}; allowed: {allowed})"
        unheld = re.fullmatch(r"argument (\S+): .* (does not fit a 64-bit float|digits long,) .*",
                              message)
        if unheld is not None:   # held_float's or held_int's refusal
            allowed = self._allowed(unheld[1])
            return message if allowed is None else f"{message} (allowed: {allowed})"
        match = re.fullmatch(r"argument (\S+): invalid (float|int) value: (.*)", message)
        if match is None:
            return message
        form = NUMBER_FORM if match[2] == "float" else INTEGER_FORM
        what = "a number" if match[2] == "float" else "a whole number"
        allowed = self._allowed(match[1])
        return (f"argument {match[1]}: {match[3]} is not {what} ({form}"
                + (f"; allowed: {allowed})" if allowed else ")"))

    def _allowed(self, option: str) -> str | None:
        """The allowed range attached to ``option`` (service.commands.numbers), if any."""
        return next((a.allowed for a in self._actions   # type: ignore[attr-defined]
                     if getattr(a, "allowed", None) and "/".join(a.option_strings) == option),
                    None)


@functools.cache
def _stating_ranges(formatter: type[argparse.HelpFormatter]) -> type[argparse.HelpFormatter]:
    """``formatter`` (argparse's default, or a subcommand's own) whose option help says
    the allowed values the option carries."""
    class StatingRanges(formatter):  # type: ignore[misc, valid-type]
        def _get_help_string(self, action: argparse.Action) -> str | None:
            return help_with_allowed(action, super()._get_help_string(action))

    return StatingRanges


class StoreOnce(argparse._StoreAction):
    """A value option given twice refused, as a request's field or query parameter given
    twice is (``service.repeated_fields``): argparse keeps the last, so `--L-mm 7.1 --L-mm
    9` answered for 9 mm and `db export --where L_mm=7.1 --where t_mm=0.5` exported every
    record at t = 0.5 mm, without a word. (``--where`` and ``--pair`` gather theirs.)"""

    GIVEN = "_options_given"     # the dests given so far, in the namespace while parsing

    def __call__(self, parser, namespace, values, option_string=None):  # type: ignore[override]
        self.once(parser, namespace)
        super().__call__(parser, namespace, values, option_string)

    def once(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace) -> None:
        """The parser's error unless this is the option's first time on the line."""
        given = namespace.__dict__.setdefault(self.GIVEN, set())
        if self.option_strings and self.dest in given:
            parser.error(f"argument {'/'.join(self.option_strings)}: given twice (allowed: "
                         "each option once)")
        given.add(self.dest)


def held_float(text: str) -> float:
    """A number option's word read by the one rule (``ascii_float``), refused as written
    where a float does not hold it: ``--tubing-mm 1e-400 0.5`` was tubing 0 mm long, as a
    JSON body's or a list option's 1e-400 is not (the parser adds the option's range)."""
    number = ascii_float(text)
    if isinstance(number, WrittenNumber):
        raise argparse.ArgumentTypeError(unheld_words(number))
    return number


def held_int(text: str) -> int:
    """An integer option's word read by the one rule (``ascii_int``); a whole number of
    more digits than Python converts (4300) refused as too long for any allowed value --
    it was told "is not a whole number", which it is (the parser adds the range)."""
    digits = text.strip().lstrip("+-")
    if is_integer_text(text) and len(digits) > sys.get_int_max_str_digits():
        raise argparse.ArgumentTypeError(f"{digits[:20]}... is {len(digits)} digits long, "
                                         "past any allowed value")
    return ascii_int(text)


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="balloon",
        description="Design bending balloon actuators: FE solves, curve database, "
                    "surrogate fits, inverse design and the REST service.")
    parser.add_argument("--version", action="version", version=f"balloon {package_version()}")
    subparsers = parser.add_subparsers(title="commands", metavar="COMMAND")
    for name in COMMAND_MODULES:
        import_module(name).register(subparsers)
    parser.set_defaults(commands=subparsers.choices)    # for _file_error's argument names
    return parser


def _file_error(args: argparse.Namespace, exc: OSError) -> str:
    """The file as the user named it and why it cannot be used, with the argument that
    named it and what that takes: `balloon calibrate nothere.csv` had said only
    "nothere.csv: No such file or directory" (the hostile-input audit of the thirty-
    seventh session)."""
    what = f"{exc.filename}: {exc.strerror}" if exc.filename and exc.strerror else str(exc)
    commands = getattr(args, "commands", None) or {}
    command = next((p for p in commands.values()
                    if p.get_default("func") is getattr(args, "func", None)), None)
    if command is None or not exc.filename:
        return what
    for action in command._actions:     # noqa: SLF001 - argparse lists them nowhere else
        value = getattr(args, action.dest, None)
        if value is not None and str(value) == str(exc.filename):
            name = (action.option_strings[-1] if action.option_strings
                    else action.metavar or action.dest.upper())
            takes = ("a file this user may read (or write, for an output)"
                     if isinstance(exc, PermissionError) else "an existing file, not a "
                     "directory" if isinstance(exc, IsADirectoryError) else "an existing file")
            return f"{name}: {what} (allowed: {takes})"
    return what


LONGEST_WORD = 100    # characters of one word an error line shows whole


def shown(what: object) -> str:
    """An error message as one readable line, whatever it quotes of the user's input: a
    control character (a CR of a CR-only file, an escape) shown escaped, not obeyed, and
    a word longer than LONGEST_WORD cut with its length said (``--model`` or a material
    of 100,000 characters was echoed whole, a 100 kB line)."""
    text = escaped(what)
    def cut(word: str) -> str:     # its closing quote and punctuation kept
        end = re.search(r"\W{0,3}$", word)[0]  # type: ignore[index]
        return f"{word[:60]}...{end} ({len(word)} characters)"

    return re.sub(rf"\S{{{LONGEST_WORD + 1},}}", lambda m: cut(m[0]), text)


def _error(what: object) -> None:
    """One line on stderr (``shown``)."""
    print(f"balloon: error: {shown(what)}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "func"):
        parser.print_help()
        return 2
    try:
        with interrupts_kept():
            return int(args.func(args) or 0)
    except (InputError, NotFoundError) as exc:
        _error(exc)
        return 2
    except (FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        # the file as the user named it and why, without Python's "[Errno 2]"
        _error(_file_error(args, exc))
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
    except Exception as exc:
        if not caused_by_interrupt(exc):   # a bug: its traceback is the report
            raise
        print("balloon: interrupted", file=sys.stderr)   # Ctrl-C inside h5py's C code
        return 130


if __name__ == "__main__":
    sys.exit(main())
