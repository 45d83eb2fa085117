"""The forty-fifth session's hostile-input audit, round six (after tests/test_hostile_s44.py):
the CLI's lists held to HTTP's one limit, unstable Ogden materials refused up front (and
records of materials the input checks now refuse still readable), free-text labels with
control, bidi or zero-width characters, and the explorer's number boxes holding "1e999".

Each test failed on the code before its fix (commit messages say which).
"""

from __future__ import annotations

import pytest
from test_cli_fuzz import run, visible_lines

from surrogate.predictor import MAX_ASKED_VALUES

DESIGN = {"L_mm": 7.1, "t_mm": 0.5}
CLI_DESIGN = ["--L-mm", "7.1", "--t-mm", "0.5"]


def one_line_error(argv: list[str]) -> str:
    """The one stderr line of ``balloon argv`` refusing it (exit 2, nothing escaped)."""
    code, out, err, escaped = run(argv)
    lines = visible_lines(err)
    assert (code, escaped) == (2, None), (code, err[:300])
    assert len(lines) == 1 and lines[0].startswith("balloon"), err[:300]
    assert "Traceback" not in err
    return lines[0]


# -- 1. the most values one question asks: one table for the CLI and HTTP --------------------

@pytest.mark.parametrize(("argv", "option"), [
    (["predict", *CLI_DESIGN, "--model", "paper", "--pressures"], "--pressures"),
    (["predict", *CLI_DESIGN, "--volumes"], "--volumes"),
    (["predict", *CLI_DESIGN, "--flow-ul-s", "2.5", "--times"], "--times"),
    (["inverse", *CLI_DESIGN, "--angles-deg"], "--angles-deg")])
def test_the_cli_asks_at_most_as_many_values_as_http(argv, option):
    """``balloon predict --pressures`` took 100,000 numbers (6 s, a 16 MB --json) where
    ``POST /v1/predict`` refuses 1001: one limit, MAX_ASKED_VALUES, named with the option."""
    values = [str(1 + i % 50) for i in range(MAX_ASKED_VALUES + 1)]
    line = one_line_error([*argv, *values[:500], ",".join(values[500:])])
    assert option in line and f"{MAX_ASKED_VALUES + 1} values" in line, line
    assert f"1 to {MAX_ASKED_VALUES} values" in line, line


def test_the_cli_still_asks_the_limit_itself():
    code, out, err, escaped = run(["predict", *CLI_DESIGN, "--model", "paper", "--pressures",
                                   *[str(i) for i in range(MAX_ASKED_VALUES)]])
    assert (code, escaped) == (0, None), err


def test_the_schemas_lists_read_the_same_limit(shipped_client):
    schemas = shipped_client.get("/openapi.json").json()["components"]["schemas"]
    for schema, name in [("PredictRequest", "pressures_pa"), ("PredictRequest", "volumes_ul"),
                         ("PredictRequest", "times_s"), ("PressureRequest", "angles_deg")]:
        prop = schemas[schema]["properties"][name]
        lists = [p for p in prop.get("anyOf", [prop]) if p.get("type") == "array"]
        assert lists[0]["maxItems"] == MAX_ASKED_VALUES, (schema, name)
