"""The service's settings: one class, read from the environment (prefix ``BALLOON_``).

Every field can be set as ``BALLOON_<NAME>``, e.g. ``BALLOON_API_KEY=...``,
``BALLOON_DB_PATH=/data/curves.h5``, ``BALLOON_CORS_ORIGINS='["https://lab.example"]'``
(lists are JSON). The defaults use the data shipped in the package
(``service/data/curves.h5`` and ``service/data/surrogate.json``), so ``balloon serve``
works right after installation.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

from pydantic import Field, SecretStr
from pydantic_settings import BaseSettings, SettingsConfigDict

DATA_DIR = Path(__file__).resolve().parent / "data"


class ServiceSettings(BaseSettings):
    """Where the data lives, who may mutate, and how much work the server accepts."""

    model_config = SettingsConfigDict(env_prefix="BALLOON_", extra="ignore")

    db_path: Path = Field(DATA_DIR / "curves.h5", description="FE curve database (HDF5)")
    surrogate_path: Path = Field(DATA_DIR / "surrogate.json",
                                 description="fitted surrogate (JSON), loaded once at start-up")
    models_dir: Path = Field(Path.home() / ".balloon" / "models",
                             description="saved calibrated models, selectable by name")
    api_key: SecretStr | None = Field(
        None, description="key for mutating endpoints (X-API-Key); unset disables them")
    workers: int = Field(1, ge=1, le=64, description="FE solve worker processes")
    queue_size: int = Field(8, ge=0, le=10_000, description="solve jobs waiting for a worker")
    job_time_limit_s: float = Field(900.0, gt=0, le=86_400,
                                    description="wall-time limit of one solve job, s")
    retry_after_s: int = Field(30, ge=1, le=3600,
                               description="Retry-After sent when the job queue is full, s")
    job_history: int = Field(1000, ge=1, le=1_000_000,
                             description="finished jobs kept in memory for GET /v1/jobs/{id}")
    max_body_bytes: int = Field(65_536, ge=1024, le=64 * 2**20,
                                description="largest accepted request body, bytes")
    cors_origins: list[str] = Field(default_factory=list,
                                    description="origins allowed by CORS; empty disables CORS")


@lru_cache
def get_settings() -> ServiceSettings:
    """The process-wide settings, read from the environment once."""
    return ServiceSettings()  # type: ignore[call-arg]  # fields come from the environment
