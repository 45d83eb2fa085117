"""The forty-seventh session's hostile-input audit, round eight (after tests/test_hostile_s46.py
and tests/test_hostile_s46b.py): a JSON body's number that a 64-bit float does not hold
(``1e-400`` read as 0, ``1e400`` or a 400-digit integer as inf) refused as written on every
route, a measured cell's likewise.

Each test failed on the code before its fix (commit messages say which), bar the guards.
"""

from __future__ import annotations

import json

import pytest
from service_fakes import assert_problem

# -- 1. a JSON number the float does not hold ------------------------------------------------

ROW = {"curve_id": "s1", "L_mm": 7.1, "t_mm": 0.5, "body_material": "pdms_1_10",
       "membrane_material": "ecoflex_00_30", "pressure_pa": 400, "angle_deg": 1.6}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    """The app with the shipped models (a tiny pressure was answered by the emulator)."""
    from fastapi.testclient import TestClient

    from service.app import create_app
    from service.settings import ServiceSettings

    tmp = tmp_path_factory.mktemp("hostile-s47")
    settings = ServiceSettings(api_key="test-key", models_dir=tmp / "models",
                               db_path=tmp / "curves.h5")
    with TestClient(create_app(settings)) as c:
        yield c


# (route, the body's text with @N where the number goes, the field, its range's words)
UNHELD_PLACES = [
    ("/v1/predict", '{"design": {"L_mm": @N}, "pressures_pa": [1000]}', "design.L_mm",
     "0.5 <= L_mm <= 60"),
    ("/v1/predict", '{"design": {}, "pressures_pa": [500, @N]}', "pressures_pa.1",
     "each 0 <= pressures_pa <= 20000"),
    ("/v1/predict", '{"design": {}, "times_s": [1], "flow_ul_s": @N}', "flow_ul_s",
     "1e-06 <= flow_ul_s <= 1000"),
    ("/v1/predict", '{"design": {"body_material": {"id": "gel", "mu_kpa": [@N], '
     '"alpha": [2]}}, "pressures_pa": [1000]}', "design.body_material.mu_kpa.0", "mu_kpa"),
    ("/v1/inverse/pressure", '{"design": {}, "angles_deg": [@N]}', "angles_deg.0",
     "each -360 <= angles_deg <= 360"),
    ("/v1/inverse", '{"target": {"kind": "angle_at_pressure", "pressure_pa": 1000, '
     '"angle_deg": @N}}', "target.angle_deg", "360"),
    ("/v1/solve", '{"design": {"t_mm": @N}}', "design.t_mm", "0.05 <= t_mm <= 5"),
    ("/v1/solve", '{"design": {}, "settings": {"max_pressure_pa": @N}}',
     "settings.max_pressure_pa", "1 <= max_pressure_pa"),
    ("/v1/calibrate", json.dumps({"rows": [ROW, {**ROW, "angle_deg": "@"}]}).replace(
        '"@"', "@N"), "rows.1.angle_deg", "a finite number"),
]


@pytest.mark.parametrize("number", ["1e-400", "-1E-400", "1e400", "1" + "0" * 400,
                                    "0." + "0" * 400 + "1", "9" * 5000],
                         ids=["1e-400", "-1E-400", "1e400", "401 digits", "0.(400)1",
                              "5000 digits"])
@pytest.mark.parametrize(("route", "body", "field", "allowed"), UNHELD_PLACES,
                         ids=[f"{r} {f}" for r, _, f, _ in UNHELD_PLACES])
def test_a_json_number_the_float_does_not_hold_is_refused_as_written(
        client, route, body, field, allowed, number):
    """Python's json read 1e-400 as 0.0 and 1e400 as inf before any schema saw them:
    ``"pressures_pa": [1e-400]`` was answered at 0 Pa, an inline material's mu [1e-400]
    "every Ogden term has mu = 0", a target's angle "got 0.0", 1e400 "Input should be a
    finite number", a 400-digit integer "Input should be a valid number", a 5000-digit one
    (past Python's 4300) "body: cannot be parsed as JSON". Each is now a 422 at its field
    naming the number as written (cut when long) and the range."""
    r = client.post(route, content=body.replace("@N", number),
                    headers={"content-type": "application/json", "X-API-Key": "test-key"})
    problem = assert_problem(r, 422, field)
    error = next(e for e in problem["errors"] if e["field"] == field)
    shown = number if len(number) <= 40 else number[:20] + "..."
    assert error["message"].startswith(f"{shown}"), error
    assert "does not fit a 64-bit float" in error["message"], error
    assert allowed in error.get("allowed", ""), error
    assert "/work" not in r.text and "/tmp" not in r.text


def test_numbers_a_float_holds_are_read_as_before(client):
    """Guard: subnormal, zero, 5e-324, 1.7e308 (refused by its range, not by the rule),
    and a body whose strings hold such text, are not this rule's."""
    r = client.post("/v1/predict", json={"design": {}, "pressures_pa": [0, 1e-320, 5e-324]})
    assert r.status_code == 200, r.text
    r = client.post("/v1/predict", content='{"design": {"L_mm": 1.7e308}, "pressures_pa": [1]}',
                    headers={"content-type": "application/json"})
    assert "does not fit" not in assert_problem(r, 422, "design.L_mm")["detail"]
    r = client.post("/v1/predict", json={"design": {"body_material": "1e400"},
                                         "pressures_pa": [1]})
    assert "does not fit" not in assert_problem(r, 422, "design.body_material")["detail"]


@pytest.mark.parametrize("cell", ['"1e-400"', "1e-400", "1" + "0" * 5000])
def test_a_data_files_cell_the_float_does_not_hold_is_refused(tmp_path, cell):
    """`balloon calibrate lab.json` (or a CSV) read a cell 1e-400 (number or text) as 0 deg,
    and a 5001-digit integer as "not valid JSON"; refused now naming row and column, as
    POST /v1/calibrate refuses it."""
    from test_cli_fuzz import run, visible_lines

    rows = [ROW, {**ROW, "pressure_pa": 800, "angle_deg": "@"}]
    path = tmp_path / "lab.json"
    path.write_text(json.dumps(rows).replace('"@"', cell))
    code, _, err, escaped = run(["calibrate", str(path), "--report", str(tmp_path / "r.json")])
    lines = visible_lines(err)
    assert code == 2 and escaped is None and len(lines) == 1, err
    assert "angle_deg: row 2:" in lines[0] and "does not fit a 64-bit float" in lines[0], err


def test_every_number_field_of_a_request_body_has_its_range():
    """Guard: the rule refuses an unheld number where a number goes, by the field's range
    (service.errors.field_range); a number field without one would read 1e-400 as 0."""
    from service.app import create_app
    from service.errors import FIELD_RANGES
    from service.settings import ServiceSettings

    spec = create_app(ServiceSettings(), load_surrogate=False).openapi()
    schemas = spec["components"]["schemas"]
    found: dict[str, bool] = {}

    def walk(schema: dict, name: str, seen: frozenset) -> None:
        ref = schema.get("$ref", "").rsplit("/", 1)[-1]
        if ref:
            if ref not in seen:
                walk(schemas[ref], name, seen | {ref})
            return
        for option in (*schema.get("anyOf", ()), *schema.get("oneOf", ())):
            walk(option, name, seen)
        kinds = schema.get("type")
        if {"number", "integer"} & set(kinds if isinstance(kinds, list) else [kinds]):
            found[name] = name in FIELD_RANGES or name == "rows"
        if "items" in schema:
            walk(schema["items"], name, seen)
        for child, sub in schema.get("properties", {}).items():
            walk(sub, child, seen)
        if isinstance(schema.get("additionalProperties"), dict):   # a measured row's cells
            walk(schema["additionalProperties"], name, seen)

    for operations in spec["paths"].values():
        for op in operations.values():
            if "requestBody" in op:
                walk(op["requestBody"]["content"]["application/json"]["schema"], "body",
                     frozenset())
    assert len(found) > 30 and all(found.values()), [n for n, ok in found.items() if not ok]


@pytest.mark.parametrize(("query", "field"), [
    ("/v1/curves?L_mm=1e400", "L_mm"),
    ("/v1/predict/plot?L_mm=7.1&t_mm=0.5&measured_pressure_pa=1e-400&measured_angle_deg=1",
     "measured_pressure_pa"),
])
def test_a_query_number_the_float_does_not_hold_is_refused_as_written(client, query, field):
    """A query's ``L_mm=1e400`` was "Input should be a finite number", and a measured point
    at ``1e-400`` Pa was drawn at 0 Pa: refused as written with the range, as in a body."""
    problem = assert_problem(client.get(query), 422, field)
    error = next(e for e in problem["errors"] if e["field"] == field)
    assert "does not fit a 64-bit float" in error["message"] and "<=" in error["allowed"]


# -- 2. a hostile grid file ------------------------------------------------------------------

PAIR = 'pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = 7.1\nt_mm = 0.5\n'


@pytest.mark.parametrize("line", [".".join(["a"] * 3000) + " = 1",
                                  "[" + ".".join(["a"] * 3000) + "]",
                                  'x = {' + " . ".join(['"a"'] * 3000) + " = 1}"])
def test_a_grid_key_of_thousands_of_dotted_parts_is_refused_before_parsing(line):
    """tomllib keeps every prefix of a dotted key: one of 50,000 parts (a 100 kB line) took
    `balloon precompute --dry-run` 88 s and 9.9 GB before "a: unknown key". Refused now
    by its length, before tomllib (3000 parts here: 0.2 s on the former code)."""
    from solver.precompute.grid import GridError, parse_grid

    with pytest.raises(GridError) as err:
        parse_grid(PAIR + line + "\n", "g.toml")
    assert "of 3000 parts" in str(err.value) and "line 4" in str(err.value), err.value
    assert "at most 10 parts" in str(err.value)


def test_a_grids_dotted_keys_as_a_grid_writes_them_are_read():
    """Guard: materials.soft.mu_kpa as a dotted key, a dotted string, a time's fraction."""
    from solver.precompute.grid import parse_grid

    grid = parse_grid('description = "a.b.c.d.e.f.g.h.i.j.k.l.m"\npairs = [["pdms_1_10", '
                      '"soft"]]\nL_mm = [7.1, 9.3]\nt_mm = 0.5\nmaterials.soft.mu_kpa = '
                      "[1.5]\nmaterials . soft . alpha = [2.0]\n", "g.toml")
    assert len(grid.points) == 2


@pytest.mark.parametrize(("text", "words"), [
    (PAIR + "[settings]\ntip = \"spring\"\nspring_k_n_per_m = 1e-400\n",
     "line 6: settings.spring_k_n_per_m: 1e-400 does not fit a 64-bit float"),
    ('pairs = [["pdms_1_10", "soft"]]\nL_mm = 7.1\nt_mm = 0.5\n[materials.soft]\n'
     "mu_kpa = [1e-400, 1.0]\nalpha = [2.0, 3.0]\n",
     "line 5: materials.soft.mu_kpa.0: 1e-400 does not fit a 64-bit float"),
    ('pairs = [["pdms_1_10", "ecoflex_00_30"]]\nL_mm = {start = 4, stop = 1e-400, num = 3}\n'
     "t_mm = 0.5\n", "line 2: L_mm.stop: 1e-400 does not fit a 64-bit float"),
])
def test_a_grid_number_the_float_does_not_hold_is_refused_as_written(text, words):
    """A grid's mu_kpa = [1e-400, 1.0] was solved as a term of mu 0 (dropped), a spring of
    1e-400 N/m told "a spring tip needs a positive stiffness", a range's stop = 1e-400 "0.0
    mm is out of range": the number named as written, with the key's range."""
    from solver.precompute.grid import GridError, parse_grid

    with pytest.raises(GridError) as err:
        parse_grid(text, "g.toml")
    assert words in str(err.value) and "allowed:" in str(err.value), err.value
