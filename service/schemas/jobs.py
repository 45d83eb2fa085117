"""POST /v1/solve and /v1/jobs/{id}: FE solves run as jobs."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from service.schemas.common import DesignIn, Schema, SolveSettingsIn

JobStatus = Literal["queued", "running", "finished", "parked", "failed", "cancelled",
                    "timed_out"]


class SolveRequest(Schema):
    model_config = ConfigDict(json_schema_extra={"examples": [
        {"design": {"L_mm": 9.1, "t_mm": 0.6}, "settings": {"mesh_level": 0}}]})

    design: DesignIn = Field(default_factory=lambda: DesignIn.model_validate({}))
    settings: SolveSettingsIn = Field(default_factory=lambda: SolveSettingsIn.model_validate({}))


class Progress(BaseModel):
    step: int = Field(0, description="converged steps so far")
    pressure_pa: float | None = Field(None, description="cavity pressure at the last step, Pa")
    volume_ul: float | None = Field(None, description="injected volume at the last step, ul")
    angle_deg: float | None = Field(None, description="bending angle at the last step, deg")
    newton_iterations: int | None = Field(None, description="Newton iterations of that step")
    cutbacks: int | None = Field(None, description="load steps cut back so far (a step that "
                                 "did not converge is retried at half its size): a curve "
                                 "standing still at one pressure while this rises is the "
                                 "solver working near a limit point, not a hang")


class Job(BaseModel):
    id: str
    status: JobStatus = Field(description="finished: the curve is stored (see "
                              "curve_status); parked: the solve finished but the database "
                              "could not be written (error says why): the result is kept "
                              "and written with the next write that succeeds")
    key: str = Field(description="the database key the result is stored under")
    created_utc: str = Field(description="when it was queued, ISO 8601 UTC")
    started_utc: str | None = Field(None, description="when a worker took it, ISO 8601 UTC")
    finished_utc: str | None = Field(None, description="when it ended, ISO 8601 UTC")
    progress: Progress
    design: dict[str, Any]
    settings: dict[str, Any]
    curve_id: str | None = Field(None, description="GET /v1/curves/{curve_id} when finished")
    curve_status: str | None = Field(None, description="the curve's status: complete, "
                                     "stopped or failed (with curve_reason)")
    curve_reason: str | None = None
    error: str | None = None
