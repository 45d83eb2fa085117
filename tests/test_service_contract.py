"""The OpenAPI contract says what the server does: every error status of each operation
documented as a problem document, response fields described with units, the calibrate
endpoint's optional security, every example valid and accepted, Allow on 405."""

from __future__ import annotations

import re

import jsonschema_rs
import pytest
from fastapi.testclient import TestClient
from service_fakes import fast_solve, settings_for

from service.app import create_app
from service.openapi import OPERATION_ERRORS, PROBLEM_JSON

UNITS = {"_mm": "mm", "_pa": "Pa", "_deg": "deg", "_ul": "ul", "_kpa": "kPa", "_utc": "UTC",
         "_mn": "mN"}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("contract")
    app = create_app(settings_for(tmp, queue_size=100), solve_fn=fast_solve,
                     write_fn=lambda d, s, c: "k" * 32, load_surrogate=False)
    from surrogate import paper_surrogate

    app.state.models.fitted = paper_surrogate()

    from service.settings import DATA_DIR
    from surrogate.emulator import load_emulator

    # the shipped emulator: the examples ask by volume and by time too, which only it answers
    app.state.models.emulator = load_emulator(DATA_DIR / "emulator.json")
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


@pytest.fixture(scope="module")
def spec(client):
    return client.get("/openapi.json").json()


def operations(spec):
    for path, ops in spec["paths"].items():
        for method, op in ops.items():
            yield path, method, op


def test_every_operation_documents_its_errors_as_problem_documents(spec):
    assert "HTTPValidationError" not in spec["components"]["schemas"]
    seen = set()
    for path, method, op in operations(spec):
        seen.add((method, path))
        documented = {int(s) for s in op["responses"] if s.startswith(("4", "5"))}
        assert documented == set(OPERATION_ERRORS[(method, path)]), (method, path)
        for status in documented:
            content = op["responses"][str(status)]["content"]
            assert list(content) == [PROBLEM_JSON], (method, path, status)
            assert content[PROBLEM_JSON]["schema"] == {"$ref": "#/components/schemas/Problem"}
    assert seen == set(OPERATION_ERRORS)


def test_calibrate_security_is_optional_and_solve_needs_the_key(spec):
    assert spec["paths"]["/v1/calibrate"]["post"]["security"] == [{}, {"APIKeyHeader": []}]
    assert spec["paths"]["/v1/solve"]["post"]["security"] == [{"APIKeyHeader": []}]


def _response_schemas(spec):
    schemas = spec["components"]["schemas"]
    names, todo = set(), []
    for _, _, op in operations(spec):
        for response in op["responses"].values():
            for media in response.get("content", {}).values():
                ref = media.get("schema", {}).get("$ref")
                if ref:
                    todo.append(ref.rsplit("/", 1)[-1])
    while todo:
        name = todo.pop()
        if name in names:
            continue
        names.add(name)
        todo += re.findall(r"#/components/schemas/(\w+)", str(schemas[name]))
    return {n: schemas[n] for n in names}


def test_response_fields_are_described_with_their_units(spec):
    for name, schema in _response_schemas(spec).items():
        for field, prop in schema.get("properties", {}).items():
            suffix = next((s for s in UNITS if field.endswith(s)), None)
            if suffix is None:
                continue
            text = prop.get("description", "")
            assert UNITS[suffix] in text, f"{name}.{field}: {text!r}"


def _examples(spec):
    """(schema, example) for every example in the document."""
    schemas = spec["components"]["schemas"]
    for name, schema in schemas.items():
        for example in schema.get("examples", []):
            yield f"#/components/schemas/{name}", example
        for field, prop in schema.get("properties", {}).items():
            for example in prop.get("examples", []):
                yield f"#/components/schemas/{name}/properties/{field}", example
    for path, method, op in operations(spec):
        for param in op.get("parameters", []):
            for example in param.get("examples", []) or []:
                yield (path, method, param["name"]), example


def _validator(spec, ref):
    schema = {"$ref": ref, "components": spec["components"]}
    return jsonschema_rs.validator_for(schema)


def test_every_example_validates_against_its_schema(spec):
    count = 0
    for ref, example in _examples(spec):
        if isinstance(ref, tuple):
            continue  # parameter examples: sent to the server below
        errors = [e.message for e in _validator(spec, ref).iter_errors(example)]
        assert not errors, (ref, example, errors)
        count += 1
    assert count >= 8


def test_every_request_body_example_is_accepted_by_the_server(client, spec):
    key = {"X-API-Key": "test-key"}
    for path, method, op in operations(spec):
        ref = (op.get("requestBody", {}).get("content", {}).get("application/json", {})
               .get("schema", {}).get("$ref"))
        if not ref:
            continue
        schema = spec["components"]["schemas"][ref.rsplit("/", 1)[-1]]
        bodies = list(schema.get("examples", []))
        for field, prop in schema.get("properties", {}).items():
            bodies += [{field: e} for e in prop.get("examples", [])]
        assert bodies, path
        for body in bodies:
            if path == "/v1/calibrate":
                body = {**body, "model": "paper"}
            r = client.request(method, path, json=body, headers=key)
            assert r.status_code in (200, 202), (path, body, r.text)


def test_every_component_example_is_accepted_inside_a_request(client, spec):
    """The design and material examples, used in the request they belong to."""
    schemas = spec["components"]["schemas"]
    material = schemas["MaterialIn"]["examples"][0]
    r = client.post("/v1/solve", headers={"X-API-Key": "test-key"},
                    json={"design": {"L_mm": 9.3, "membrane_material": material}})
    assert r.status_code == 202, r.text
    for design in schemas["DesignIn"]["examples"]:
        r = client.post("/v1/predict", json={"design": design, "pressures_pa": [500]})
        assert r.status_code == 200, r.text
    for settings in schemas["SolveSettingsIn"]["examples"]:
        r = client.post("/v1/solve", headers={"X-API-Key": "test-key"},
                        json={"design": {"L_mm": 9.7}, "settings": settings})
        assert r.status_code == 202, r.text


def test_405_names_every_method_of_the_path(client, spec):
    for path, ops in spec["paths"].items():
        concrete = re.sub(r"\{[^}]+\}", "0" * 32, path)
        unused = next(m for m in ("put", "patch", "post", "delete") if m not in ops)
        r = client.request(unused, concrete)
        assert r.status_code == 405, (path, unused)
        assert r.headers["content-type"] == PROBLEM_JSON
        assert r.headers["allow"] == ", ".join(sorted(m.upper() for m in ops)), path


@pytest.mark.parametrize("path", ["/", "/docs", "/redoc", "/openapi.json",
                                  "/static/explorer/js/app.js"])
def test_405_outside_the_contract_names_the_methods_too(client, path):
    # the page, the docs and the static files answered 405 with an empty Allow (an audit
    # of the thirty-fifth session)
    r = client.post(path)
    assert r.status_code == 405 and r.headers["content-type"] == PROBLEM_JSON
    assert r.headers["allow"] == "GET, HEAD"
