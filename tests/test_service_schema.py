"""A bounded property-based run of the OpenAPI schema (schemathesis): no input gives a 5xx,
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
from schemathesis.checks import not_a_server_error
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
    return schemathesis.openapi.from_asgi("/openapi.json", app)


KEY = {"X-API-Key": "test-key"}  # settings_for's key
schema = build_schema()  # at import: schemathesis parametrizes over its operations


@schema.parametrize()
@settings(max_examples=15, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                 HealthCheck.function_scoped_fixture])
def test_no_input_gives_a_server_error(case):
    response = case.call_and_validate(headers=KEY, checks=[not_a_server_error])
    if response.status_code >= 400:
        assert response.headers["content-type"][0] == "application/problem+json"
