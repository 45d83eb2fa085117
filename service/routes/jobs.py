"""POST /v1/solve (202 + job), GET /v1/jobs/{id} (progress), DELETE /v1/jobs/{id} (cancel)."""

from __future__ import annotations

from dataclasses import replace
from typing import Annotated, Any

from fastapi import APIRouter, Path
from fastapi.responses import JSONResponse

from service.convert import to_design, to_settings
from service.deps import ApiKeyDep, JobsDep, SettingsDep
from service.errors import ConflictError, FieldError, UnavailableError
from service.jobs import JobState
from service.schemas import Job, SolveRequest
from service.schemas.jobs import Progress
from service.store_access import stored_key

router = APIRouter(prefix="/v1", tags=["jobs"])

JOB_ID = Path(description="the job id (32 hex digits; any other text is "
              "not found)", examples=["0123456789abcdef0123456789abcdef"])


def job_view(job: JobState) -> Job:
    return Job(id=job.id, status=job.status, key=job.key,  # type: ignore[arg-type]
               created_utc=job.created_utc, started_utc=job.started_utc,
               finished_utc=job.finished_utc, progress=Progress(**job.progress),
               design=job.design.as_dict(), settings=job.settings.as_dict(),
               curve_id=job.curve_id,
               curve_status=job.curve_status, curve_reason=job.curve_reason, error=job.error)


@router.post("/solve", status_code=202, response_model=Job, dependencies=[ApiKeyDep],
             summary="Queue an FE solve of a design that is not in the database")
def solve(request: SolveRequest, jobs: JobsDep, settings: SettingsDep) -> JSONResponse:
    """Returns the job (202, ``Location: /v1/jobs/{id}``); poll it for progress. The
    same design and settings while a job for them is active return that job."""
    from solver.store import record_key

    design = to_design(request.design)
    solver_settings = to_settings(request.settings)
    _check_size(design, solver_settings, settings.max_solve_dofs)
    _check_storable(settings.db_path)
    key = record_key(design, solver_settings)
    if stored_key(settings.db_path, key):
        raise ConflictError(f"this design and settings are already in the database as "
                            f"curve {key}: GET /v1/curves/{key}", curve_id=key)
    job = jobs.submit(design, solver_settings, key)
    return JSONResponse(job_view(job).model_dump(), status_code=202,
                        headers={"Location": f"/v1/jobs/{job.id}"})


def _check_storable(db_path: Any) -> None:
    """503 before queueing when the database cannot take the finished solve (a
    directory, a device, a second hard link, a directory that takes no file:
    ``solver.store.locking.unwritable``): the server's setting, not the client's input,
    and a job would only fail after its solve. The words name the file, not its path."""
    from solver.store.locking import unwritable

    why = unwritable(db_path)
    if why:
        raise UnavailableError(f"this server cannot store a solve: its curve database "
                               f"(BALLOON_DB_PATH) {why}; nothing was queued")


def _check_size(design: Any, solver_settings: Any, max_dofs: int) -> None:
    """422 naming ``settings.mesh_level`` (or the design, when even the coarsest mesh is
    too big) when the solve would build more than ``max_dofs`` degrees of freedom
    (``solver.mesh.estimated_dofs``): one such request took 17.8 GB before its first
    step, and a job's memory is not otherwise bounded."""
    from solver.mesh import estimated_dofs

    dofs = estimated_dofs(design, solver_settings)
    if dofs <= max_dofs:
        return
    fits = [level for level in range(solver_settings.mesh_level)
            if estimated_dofs(design, replace(solver_settings, mesh_level=level)) <= max_dofs]
    what = (f"this design at mesh level {solver_settings.mesh_level} "
            f"({solver_settings.element}, {solver_settings.mesh_divisions}) has about "
            f"{dofs:,} degrees of freedom, more than this server solves ({max_dofs:,}, "
            "BALLOON_MAX_SOLVE_DOFS)")
    if fits:
        raise FieldError(("body", "settings", "mesh_level"), what,
                         f"0 <= mesh_level <= {fits[-1]} for this design")
    raise FieldError(("body", "design"), what, "a smaller design (L_mm, body_length_mm, "
                     "b_mm, W_mm) or element hex1, or `balloon solve` on a machine with "
                     "the memory")


@router.get("/jobs/{job_id}", response_model=Job, summary="A job's status and progress")
def get_job(job_id: Annotated[str, JOB_ID], jobs: JobsDep) -> Job:
    return job_view(jobs.get(job_id))


@router.delete("/jobs/{job_id}", response_model=Job, dependencies=[ApiKeyDep],
               summary="Cancel a queued or running job")
def cancel_job(job_id: Annotated[str, JOB_ID], jobs: JobsDep) -> Job:
    return job_view(jobs.cancel(job_id))
