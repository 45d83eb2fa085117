"""GET /v1/health: liveness and what is loaded (files by their name, never a path)."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field


class DatabaseStatus(BaseModel):
    name: str = Field(description="the curve database's file name (its directory is not "
                      "shown)")
    present: bool
    records: int | None = Field(None, description="records stored; null when absent or "
                                "unreadable")
    error: str | None = Field(None, description="why the database cannot be read")


class SurrogateStatus(BaseModel):
    loaded: bool
    name: str | None = Field(None, description="the fitted surrogate's name")
    file: str = Field(description="the surrogate file's name (its directory is not shown)")
    families: int = Field(0, description="material/geometry families it covers")
    sha256: str | None = Field(None, description="SHA-256 of the loaded file's bytes: which "
                               "model file answers (a batch's record of its model; the "
                               "same as `sha256sum` of the file)")
    error: str | None = Field(None, description="why it is not loaded")


class JobsStatus(BaseModel):
    workers: int = Field(description="FE solve worker processes")
    running: int = Field(description="jobs being solved now")
    queued: int = Field(description="jobs waiting for a worker")
    queue_size: int = Field(description="jobs that may wait; one more is refused with 503")


class Health(BaseModel):
    status: Literal["ok", "degraded"] = Field(
        "ok", description='"degraded" when an endpoint answers 503 because of the server\'s '
        "data (no or damaged database, no fitted surrogate); `problems` says why")
    problems: list[str] = Field([], description="what is degraded, one sentence each")
    version: str = Field(description="balloon-actuator package version")
    database: DatabaseStatus
    surrogate: SurrogateStatus = Field(description="the fitted exponential model")
    emulator: SurrogateStatus | None = Field(None, description="the design-space emulator "
                                             "(the default model); families = its groups")
    jobs: JobsStatus
