"""A bounded property-based run of the OpenAPI schema (schemathesis, every check it has:
``schemathesis run --checks all``): no input gives a 5xx, every status, content type,
header and body is the documented one, invalid data is rejected and valid data accepted,
and every error is a problem document.

The app serves a small synthetic database and the paper's surrogate as the fitted one.
Every request carries the valid API key, so the bodies of the mutating endpoints (solve,
cancel, calibrate with save) are explored past the key check; the solve workers are not
started (lifespan does not run), so a queued job never runs, and the queue is large
enough that it never fills (a full queue's 503 is tested in test_service_jobs.py).
The 401/403 answers without a key are tested in test_service_api.py.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis import checks
from schemathesis.core.parameters import ParameterLocation
from service_fakes import fast_solve, make_curve, settings_for

from service.app import create_app
from solver.design import Design
from solver.settings import SolverSettings
from solver.store import CurveStore, make_record
from surrogate import paper_surrogate


def build_schema():
    tmp = Path(tempfile.mkdtemp(prefix="balloon-schema-"))
    with CurveStore(tmp / "curves.h5", mode="a") as db:
        for L_mm in (4.1, 7.1):
            db.put(make_record(Design(L_mm=L_mm), SolverSettings(mesh_level=0), make_curve()))
    app = create_app(settings_for(tmp, db_path=tmp / "curves.h5", queue_size=10_000),
                     solve_fn=fast_solve,
                     write_fn=lambda d, s, c: "0" * 32, load_surrogate=False)
    app.state.models.fitted = paper_surrogate()  # real code paths, shipped constants
    app.state.models.emulator = app.state.models.fitted
    return schemathesis.openapi.from_asgi("/openapi.json", app, config=CONFIG)


KEY = {"X-API-Key": "test-key"}  # settings_for's key
checks.load_all_checks()
# `--checks all`: every check schemathesis has, the two data checks with the statuses
# this API documents for them --
# positive_data_acceptance: a schema-valid request may still break a rule JSON Schema
#   cannot state (mu_kpa and alpha of equal length, a chamber that fits its body, a
#   design outside the fitted families or the emulator's box, an inline material reusing
#   a preset id), answered 422; the test below then requires that the 422 names its field;
# negative_data_rejection: 413 (a body over the limit) is a rejection too.
CHECK_STATUSES = {
    "positive_data_acceptance": ["2xx", "401", "403", "404", "409", "422"],
    "negative_data_rejection": ["400", "401", "403", "404", "405", "406", "409", "413",
                                "415", "422"],
}
CONFIG = schemathesis.Config.from_dict({"checks": {
    name: {"expected-statuses": statuses} for name, statuses in CHECK_STATUSES.items()}})
ALL_CHECKS = checks.CHECKS.get_all()
REJECTED = {401, 403, 404, 405, 409, 413, 422}
schema = build_schema()  # at import: schemathesis parametrizes over its operations


@schema.parametrize()
@settings(max_examples=15, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                 HealthCheck.function_scoped_fixture])
def test_no_input_gives_a_server_error(case):
    response = case.call_and_validate(headers=KEY, checks=ALL_CHECKS)
    if response.status_code >= 400:
        assert response.headers["content-type"][0] == "application/problem+json"
    if response.status_code == 422:
        errors = response.json()["errors"]
        assert errors and all(e["field"] and e["message"] for e in errors), response.text
    if case.meta is not None and case.meta.is_negative_at(ParameterLocation.BODY):
        assert response.status_code in REJECTED, response.text  # an invalid body is refused
