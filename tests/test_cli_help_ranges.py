"""Every number option's ``--help`` states its allowed range, the one its check and its
parser error use (``service.commands.numbers.help_with_allowed``): a new user reading
``balloon predict --help`` saw no range for --L-mm, --pressures, --flow-ul-s or -n, and
``balloon solve --help`` said --flow-ul-s took up to 1e6 ul/s where the solver refuses
above 1000 (forty-ninth session's new-user audit)."""

from __future__ import annotations

import argparse
import re

import pytest

from service.cli import build_parser, main
from solver.settings import MAX_FLOW_UL_S

# an option whose range the command states in no table the parser can read at start-up
# (surrogate.emulator.adaptive.MAX_ADAPTIVE: importing it costs the emulator's imports)
UNSTATED = {"--adaptive"}


def _commands(parser: argparse.ArgumentParser, name: str = "balloon"):
    yield name, parser
    for action in parser._actions:  # noqa: SLF001
        if isinstance(action, argparse._SubParsersAction):  # noqa: SLF001
            for sub, child in action.choices.items():
                yield from _commands(child, f"{name} {sub}")


def _number_options():
    for name, parser in _commands(build_parser()):
        for action in parser._actions:  # noqa: SLF001
            numeric = action.type in (float, int) or hasattr(action, "allowed")
            if action.option_strings and numeric and action.option_strings[-1] not in UNSTATED:
                yield pytest.param(name, parser, action, id=f"{name} {action.option_strings[-1]}")


def _flat(text: str) -> str:
    return re.sub(r"\s+", " ", text)


@pytest.mark.parametrize(("name", "parser", "action"), list(_number_options()))
def test_number_option_help_states_its_range(name, parser, action):
    allowed = getattr(action, "allowed", None)
    assert allowed, f"{name} {action.option_strings[-1]} carries no allowed range"
    assert _flat(allowed) in _flat(parser.format_help()), (
        f"`{name} --help` does not state {action.option_strings[-1]}'s range {allowed!r}")


def test_solve_help_states_the_flow_limit_the_solver_checks(capsys):
    with pytest.raises(SystemExit):
        main(["solve", "--help"])
    text = _flat(capsys.readouterr().out)
    flow = re.search(r"--flow-ul-s FLOW_UL_S (.*?) --bulk-ratio", text)[1]
    assert f"{MAX_FLOW_UL_S:g} ul/s" in flow and "1e6" not in flow


def test_predict_help_names_the_emulators_box(capsys):
    with pytest.raises(SystemExit):
        main(["predict", "--help"])
    text = _flat(capsys.readouterr().out)
    assert "chamber length, mm (the emulator's box 4 to 18 at W = 3; allowed: 0.5 to 60 mm)" in text


def _without_help(parser, path):
    """(command, option) of every argument of ``parser`` and its subcommands whose
    ``--help`` line says nothing but its name."""
    import argparse

    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _without_help(sub, [*path, name])
        elif not isinstance(action, argparse._HelpAction) and not action.help:
            yield " ".join(path), "/".join(action.option_strings) or action.dest


def test_every_argument_of_every_command_says_what_it_is():
    """``serve --log-level``, ``db export --where / --status / --format`` and ``db ls
    --status`` were listed in --help with their name alone (the forty-ninth session's
    new-user audit)."""
    from service.cli import build_parser

    assert list(_without_help(build_parser(), ["balloon"])) == []
