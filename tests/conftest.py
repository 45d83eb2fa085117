"""Shared pytest configuration: heavy finite-element cases are opt-in (--runslow)."""

import pytest


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--runslow", action="store_true", default=False,
                     help="also run tests marked slow (heavy FE cases)")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if config.getoption("--runslow"):
        return
    skip = pytest.mark.skip(reason="slow FE case: run with --runslow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)
