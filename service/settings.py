"""The service's settings: one class, read from the environment (prefix ``BALLOON_``).

Every field can be set as ``BALLOON_<NAME>``, e.g. ``BALLOON_API_KEY=...``,
``BALLOON_DB_PATH=/data/curves.h5``, ``BALLOON_CORS_ORIGINS='["https://lab.example"]'``
(lists are JSON). The defaults use the data shipped in the package
(``service/data/curves.h5`` and ``service/data/surrogate.json``), so ``balloon serve``
works right after installation.
"""

from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

from pydantic import Field, SecretStr, ValidationError, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict, SettingsError

from solver.errors import InputError

ENV_PREFIX = "BALLOON_"

DATA_DIR = Path(__file__).resolve().parent / "data"


class ServiceSettings(BaseSettings):
    """Where the data lives, who may mutate, and how much work the server accepts."""

    model_config = SettingsConfigDict(env_prefix=ENV_PREFIX, extra="ignore")

    db_path: Path = Field(DATA_DIR / "curves.h5", description="FE curve database (HDF5)")
    surrogate_path: Path = Field(DATA_DIR / "surrogate.json",
                                 description="fitted exponential model (JSON), loaded once at "
                                 "start-up")
    emulator_path: Path = Field(DATA_DIR / "emulator.json",
                                description="design-space emulator (JSON), the default model, "
                                "loaded once at start-up")
    models_dir: Path = Field(Path.home() / ".balloon" / "models",
                             description="saved calibrated models, selectable by name")
    api_key: SecretStr | None = Field(
        None, description="key for mutating endpoints (X-API-Key); unset disables them")
    workers: int = Field(1, ge=1, le=64, description="FE solve worker processes")
    queue_size: int = Field(8, ge=0, le=10_000, description="solve jobs waiting for a worker")
    job_time_limit_s: float = Field(900.0, gt=0, le=86_400, allow_inf_nan=False,
                                    description="wall-time limit of one solve job, s")
    max_solve_dofs: int = Field(
        500_000, ge=1_000, le=100_000_000,
        description="largest FE model a solve job may build, in degrees of freedom "
        "(estimated from the design's mesh before queueing; mesh level 2 of the box's "
        "longest chamber is 472k, the standard design's 275k). A solve's memory grows "
        "faster than its size: one with 2.0M took 17.8 GB before its first step")
    retry_after_s: int = Field(30, ge=1, le=3600,
                               description="Retry-After sent when the job queue is full, s")
    job_history: int = Field(1000, ge=1, le=1_000_000,
                             description="finished jobs kept in memory for GET /v1/jobs/{id}")
    max_body_bytes: int = Field(65_536, ge=1024, le=64 * 2**20,
                                description="largest accepted request body, bytes")
    max_calibration_body_bytes: int = Field(
        4 * 2**20, ge=1024, le=64 * 2**20,
        description="largest accepted body of POST /v1/calibrate, bytes: a lab's data set "
        "(the schema's 20,000 rows at ~150 bytes a row; 340 rows filled the general limit)")
    max_calibration_curves: int = Field(
        200, ge=2, le=20_000,
        description="most curves (distinct curve_id) one POST /v1/calibrate calibrates: the "
        "loop's work grows with them (5,000 curves of 4 readings took over 5 min CPU "
        "against the paper's model; a lab's file is some 20)")
    max_calibration_designs: int = Field(
        20, ge=1, le=20_000,
        description="most nominal designs (material pair, T, b, h, L, t) one POST "
        "/v1/calibrate calibrates: each is a curve of the baseline (100 designs took "
        "100 s CPU against the emulator; a lab's file has a few)")
    cors_origins: list[str] = Field(default_factory=list,
                                    description="origins allowed by CORS; empty disables CORS")

    @field_validator("api_key")
    @classmethod
    def _sendable(cls, key: SecretStr | None) -> SecretStr | None:
        """A key a client can send in its X-API-Key header: ``BALLOON_API_KEY=`` (a
        compose file's unset ``${KEY}``) or a key ending in a space (a .env line) was
        taken, and every mutating request refused (an HTTP header's value has no spaces
        at its ends, nor control characters). The key itself is never echoed."""
        text = key.get_secret_value() if key is not None else None
        if text is None:
            return key
        if not text.strip():
            raise ValueError("is empty (or spaces only): no client could send it")
        if text != text.strip():
            raise ValueError("begins or ends with a space or tab, which an HTTP header's "
                             "value does not carry: no client could send it")
        if any((ord(c) < 32 and c != "\t") or ord(c) == 127 for c in text):
            raise ValueError("holds a control character, which an HTTP header's value does "
                             "not carry: no client could send it")
        return key


def settings_from_environment() -> ServiceSettings:
    """``ServiceSettings()`` read from the environment; a bad value is an InputError
    naming its variable and the allowed range (``balloon serve`` prints it on one line)."""
    try:
        return ServiceSettings()  # type: ignore[call-arg]  # fields come from the environment
    except ValidationError as exc:
        errors = exc.errors()
        name = str(errors[0]["loc"][0]) if errors[0].get("loc") else ""
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        message = (str(errors[0]["ctx"]["error"]) if errors[0]["type"] == "value_error"
                   else errors[0]["msg"])      # a validator's own words, as over HTTP
        raise InputError(ENV_PREFIX + name.upper(), message + more, _allowed(name)) from None
    except SettingsError as exc:  # a list that is not JSON
        match = re.search(r'field "(\w+)"', str(exc))
        name = match.group(1) if match else ""
        raise InputError(ENV_PREFIX + name.upper(), "cannot be parsed", _allowed(name)
                         ) from None


def _allowed(name: str) -> str | None:
    from service.schemas._ranges import field_ranges

    if name == "cors_origins":
        return 'a JSON list of origins, e.g. ["https://lab.example"]'
    if name == "api_key":
        return ("unset (the mutating endpoints off), or a key of printable characters, "
                "without spaces at its ends")
    return field_ranges([ServiceSettings]).get(name)


@lru_cache
def get_settings() -> ServiceSettings:
    """The process-wide settings, read from the environment once."""
    return settings_from_environment()
