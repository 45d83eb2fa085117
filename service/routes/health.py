"""GET /v1/health: liveness, and which database and surrogate are loaded."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from fastapi import APIRouter

from service.deps import JobsDep, ModelsDep, SettingsDep
from service.schemas import Health
from service.schemas.health import DatabaseStatus, JobsStatus, SurrogateStatus
from service.store_access import database_state
from solver.precompute.parking import parked_files
from solver.store.locking import unwritable

router = APIRouter(prefix="/v1", tags=["health"])


def _version() -> str:
    try:
        return version("balloon-actuator")
    except PackageNotFoundError:
        return "0+unknown"


VERSION = _version()


@router.get("/health", response_model=Health, summary="Liveness and loaded data")
async def health(settings: SettingsDep, models: ModelsDep, jobs: JobsDep) -> Health:
    """Cheap by design (the database's index is re-read only when the file changes): used
    by the Docker HEALTHCHECK, which needs 200 (the process is alive) also when
    ``status`` is "degraded" (no or damaged database, no fitted surrogate)."""
    fitted = models.fitted
    present = settings.db_path.is_file()
    records, db_error = database_state(settings.db_path)
    problems = []
    if not present:
        problems.append(f"no curve database {settings.db_path.name}: /v1/curves answers 503")
    elif db_error:
        problems.append(f"{db_error}: /v1/curves answers 503")
    unstorable = unwritable(settings.db_path) if settings.api_key else None  # else 403
    if unstorable:
        problems.append(f"the curve database {unstorable}: POST /v1/solve answers 503")
    parked = len(parked_files(settings.db_path))
    if parked:
        problems.append(f"{parked} finished solve result(s) parked: the curve database "
                        f"{settings.db_path.name} could not be written; they are written "
                        "with the next write that succeeds")
    if fitted is None:
        problems.append(f"no fitted surrogate ({models.fitted_error}): model \"exponential\" "
                        "answers 503; \"paper\" answers")
    emulator = models.emulator
    if emulator is None:
        problems.append(f"no emulator ({models.emulator_error or 'not loaded'}): the default "
                        "model \"emulator\" answers 503")
    if settings.models_dir.exists() and not settings.models_dir.is_dir():
        problems.append("the models directory (BALLOON_MODELS_DIR) is not a directory: "
                        "saving a calibration answers 503")
    return Health(
        status="degraded" if problems else "ok", problems=problems, version=VERSION,
        database=DatabaseStatus(name=settings.db_path.name, present=present,
                                records=records, error=db_error),
        surrogate=SurrogateStatus(
            loaded=fitted is not None, file=settings.surrogate_path.name,
            name=getattr(fitted, "name", None), error=models.fitted_error,
            sha256=models.fitted_sha256 if fitted is not None else None,
            families=len(getattr(fitted, "families", []) or [])),
        emulator=SurrogateStatus(
            loaded=emulator is not None,
            file=models.emulator_path.name if models.emulator_path else "",
            name=getattr(emulator, "name", None), error=models.emulator_error,
            sha256=models.emulator_sha256 if emulator is not None else None,
            families=len(getattr(emulator, "pairs", {}) or {})),
        jobs=JobsStatus(**jobs.stats()))
