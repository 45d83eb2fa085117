"""GET /v1/health: liveness, and which database and surrogate are loaded."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from fastapi import APIRouter

from service.deps import JobsDep, ModelsDep, SettingsDep
from service.schemas import Health
from service.schemas.health import DatabaseStatus, JobsStatus, SurrogateStatus
from service.store_access import record_count

router = APIRouter(prefix="/v1", tags=["health"])


def _version() -> str:
    try:
        return version("balloon-actuator")
    except PackageNotFoundError:
        return "0+unknown"


VERSION = _version()


@router.get("/health", response_model=Health, summary="Liveness and loaded data")
async def health(settings: SettingsDep, models: ModelsDep, jobs: JobsDep) -> Health:
    """Cheap by design (the record count is re-read only when the file changes): used by
    the Docker HEALTHCHECK."""
    fitted = models.fitted
    return Health(
        version=VERSION,
        database=DatabaseStatus(path=str(settings.db_path), present=settings.db_path.is_file(),
                                records=record_count(settings.db_path)),
        surrogate=SurrogateStatus(
            loaded=fitted is not None, path=str(settings.surrogate_path),
            name=getattr(fitted, "name", None), error=models.fitted_error,
            families=len(getattr(fitted, "families", []) or [])),
        jobs=JobsStatus(**jobs.stats()))
