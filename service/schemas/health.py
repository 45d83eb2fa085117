"""GET /v1/health: liveness and what is loaded."""

from __future__ import annotations

from pydantic import BaseModel


class DatabaseStatus(BaseModel):
    path: str
    present: bool
    records: int | None = None


class SurrogateStatus(BaseModel):
    loaded: bool
    name: str | None = None
    path: str
    families: int = 0
    error: str | None = None


class JobsStatus(BaseModel):
    workers: int
    running: int
    queued: int
    queue_size: int


class Health(BaseModel):
    status: str = "ok"
    version: str
    database: DatabaseStatus
    surrogate: SurrogateStatus
    jobs: JobsStatus
