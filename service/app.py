"""The FastAPI application: ``create_app(settings) -> FastAPI``.

Start-up (lifespan) loads the fitted surrogate once and starts the solve workers;
shut-down stops them. Nothing heavy happens at import time. Routers, one per
resource, live in ``service.routes``; every error is answered by
``service.errors`` as ``application/problem+json``.
"""

from __future__ import annotations

from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from typing import Any

from fastapi import Depends, FastAPI
from fastapi.middleware.cors import CORSMiddleware

from service._worker import default_solve
from service.errors import install_error_handlers
from service.jobs import JobManager
from service.middleware import (
    BodyLimitMiddleware,
    HeadAsGetMiddleware,
    IdentityBodyMiddleware,
    ProblemOnlyMiddleware,
)
from service.models import ModelRegistry
from service.openapi import install_contract
from service.repeated_fields import refuse_repeated_fields
from service.routes import calibration, curves, health, inverse, jobs, materials, predict
from service.routes.pages import install_pages
from service.settings import ServiceSettings, get_settings
from service.store_access import ResultWriter
from service.unheld_numbers import refuse_unheld_numbers
from service.unread_query import refuse_unread_query

DESCRIPTION = """\
Design questions about bending balloon actuators (two bonded silicone layers).

* **predict** and **inverse** answer in microseconds from a surrogate of the FE model;
* **curves** serves the stored finite-element records;
* **solve** queues a new FE solve (API key in `X-API-Key`); poll **jobs** for progress.

Units are in every field name (`_mm`, `_pa`, `_deg`). Errors are RFC 9457
`application/problem+json` documents naming the field and its allowed range.
"""


def create_app(settings: ServiceSettings | None = None, *,
               solve_fn: Callable[..., Any] | None = None,
               write_fn: Callable[[Any, Any, Any], str] | None = None,
               load_surrogate: bool = True) -> FastAPI:
    """Build the app. ``solve_fn`` and ``write_fn`` replace the FE solve and the database
    writer (tests); ``solve_fn`` must be picklable (a module-level function)."""
    settings = settings or get_settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        if load_surrogate:
            app.state.models.load_fitted()
        app.state.jobs.start()
        try:
            yield
        finally:
            app.state.jobs.shutdown()

    app = FastAPI(title="Balloon actuator design service", version=health.VERSION,
                  description=DESCRIPTION, lifespan=lifespan,
                  docs_url=None, redoc_url=None,  # served from local files by install_pages
                  dependencies=[Depends(refuse_repeated_fields),  # a field given twice
                                Depends(refuse_unread_query),  # a query string ignored
                                Depends(refuse_unheld_numbers)])  # 1e-400 read as 0
    app.state.settings = settings
    app.state.models = ModelRegistry(settings.surrogate_path, settings.models_dir,
                                     settings.emulator_path)
    app.state.jobs = JobManager(
        solve_fn or default_solve, write_fn or ResultWriter(settings.db_path),
        workers=settings.workers, queue_size=settings.queue_size,
        time_limit_s=settings.job_time_limit_s, retry_after_s=settings.retry_after_s,
        history=settings.job_history)

    install_error_handlers(app)
    install_contract(app)
    for module in (health, materials, predict, inverse, curves, jobs):
        app.include_router(module.router)
    # Calibration (POST /v1/calibrate, GET /v1/effects) is included here:
    app.include_router(calibration.router)
    install_pages(app)  # the explorer at /, /docs and /redoc, all offline (service/static)

    app.add_middleware(BodyLimitMiddleware, max_bytes=settings.max_body_bytes,
                       per_path={"/v1/calibrate": settings.max_calibration_body_bytes})
    app.add_middleware(IdentityBodyMiddleware)  # a gzip body: 415, never decoded
    if settings.cors_origins:
        app.add_middleware(CORSMiddleware, allow_origins=settings.cors_origins,
                           allow_methods=["GET", "POST", "DELETE"],
                           allow_headers=["Content-Type", "X-API-Key"],
                           expose_headers=["Location", "Retry-After"])
    app.add_middleware(ProblemOnlyMiddleware)  # Starlette's own text/plain errors
    app.add_middleware(HeadAsGetMiddleware)    # outermost: HEAD is GET without the body
    return app
