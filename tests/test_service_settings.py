"""Settings from the environment, the one error-to-HTTP mapping, and the range registry."""

from __future__ import annotations

import argparse

import pytest
from pydantic import BaseModel, Field, ValidationError

from service.commands import serve
from service.errors import (
    AuthError,
    ConflictError,
    FieldError,
    PayloadTooLargeError,
    QueueFullError,
    UnavailableError,
    problem_for,
)
from service.schemas import REQUEST_MODELS
from service.schemas._ranges import field_ranges
from service.settings import DATA_DIR, ServiceSettings, get_settings
from solver.errors import BalloonError, ConvergenceError, InputError, NotFoundError
from surrogate import OutOfFamilyError


def test_settings_come_from_balloon_environment_variables(monkeypatch, tmp_path):
    monkeypatch.setenv("BALLOON_DB_PATH", str(tmp_path / "x.h5"))
    monkeypatch.setenv("BALLOON_API_KEY", "s3cret")
    monkeypatch.setenv("BALLOON_WORKERS", "3")
    monkeypatch.setenv("BALLOON_CORS_ORIGINS", '["https://lab.example"]')
    get_settings.cache_clear()
    try:
        s = get_settings()
        assert s.db_path == tmp_path / "x.h5" and s.workers == 3
        assert s.api_key.get_secret_value() == "s3cret" and "s3cret" not in repr(s)
        assert s.cors_origins == ["https://lab.example"]
        assert get_settings() is s  # read once
    finally:
        get_settings.cache_clear()


def test_default_settings_use_the_shipped_data(monkeypatch):
    for name in ("BALLOON_DB_PATH", "BALLOON_SURROGATE_PATH", "BALLOON_API_KEY"):
        monkeypatch.delenv(name, raising=False)
    s = ServiceSettings()
    assert s.db_path == DATA_DIR / "curves.h5"
    assert s.surrogate_path == DATA_DIR / "surrogate.json"
    assert s.api_key is None  # mutating endpoints stay off until a key is set


def test_bad_settings_are_refused(monkeypatch):
    monkeypatch.setenv("BALLOON_WORKERS", "0")
    with pytest.raises(ValidationError, match="workers"):
        ServiceSettings()


@pytest.mark.parametrize("name, value, allowed", [
    ("BALLOON_WORKERS", "abc", "1 <= workers <= 64"),
    ("BALLOON_WORKERS", "0", "1 <= workers <= 64"),
    ("BALLOON_MAX_BODY_BYTES", "10", "1024 <= max_body_bytes <= 67108864"),  # 64 MiB
    ("BALLOON_JOB_TIME_LIMIT_S", "-1", "0 < job_time_limit_s <= 86400"),
    ("BALLOON_CORS_ORIGINS", "https://lab.example", "a JSON list of origins"),
])
def test_serve_with_a_bad_setting_is_one_line_and_exit_2(monkeypatch, capsys, name, value,
                                                         allowed):
    import uvicorn

    from service.cli import main

    def must_not_start(*args, **kwargs):
        raise AssertionError("the server started with a bad setting")

    monkeypatch.setattr(uvicorn, "run", must_not_start)
    monkeypatch.setenv(name, value)
    get_settings.cache_clear()
    try:
        assert main(["serve", "--port", "8011"]) == 2
    finally:
        get_settings.cache_clear()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"balloon: error: {name}:"), err
    assert f"(allowed: {allowed}" in err[0]


@pytest.mark.parametrize("exc, status, kind", [
    (InputError("t_mm", "bad", "0 < t_mm"), 422, "invalid-input"),
    (FieldError(("body", "design", "t_mm"), "bad"), 422, "invalid-input"),
    (OutOfFamilyError("no family"), 422, "out-of-family"),
    (NotFoundError("no such record"), 404, "not-found"),
    (AuthError("no key"), 401, "unauthorised"),
    (AuthError("wrong key", status=403), 403, "unauthorised"),
    (ConflictError("done"), 409, "conflict"),
    (PayloadTooLargeError("big"), 413, "payload-too-large"),
    (QueueFullError("full", retry_after_s=9), 503, "queue-full"),
    (UnavailableError("no db"), 503, "unavailable"),
    (ConvergenceError("Newton"), 422, "solver-error"),
    (BalloonError("other"), 422, "balloon"),
    (RuntimeError("bug"), 500, "internal"),
])
def test_every_error_class_maps_to_one_status(exc, status, kind):
    problem = problem_for(exc)
    assert (problem.status, problem.kind) == (status, kind)
    if isinstance(exc, QueueFullError):
        assert problem.headers == {"Retry-After": "9"}
    if status == 500:
        assert "bug" not in problem.detail  # internals never reach the client


def test_field_error_keeps_the_request_path():
    problem = problem_for(FieldError(("body", "design", "t_mm"), "too thick", "t_mm <= 5"))
    assert problem.errors == [{"loc": ["body", "design", "t_mm"], "field": "design.t_mm",
                               "message": "too thick", "allowed": "t_mm <= 5"}]


def test_every_bounded_request_field_has_one_range():
    ranges = field_ranges(REQUEST_MODELS)
    assert ranges["t_mm"] == "0.05 <= t_mm <= 5"  # solver.design.LIMITS_MM
    assert ranges["p_max_pa"] == "0 < p_max_pa <= 20000"

    class Clash(BaseModel):
        t_mm: float = Field(1.0, ge=0.0, le=1.0)

    with pytest.raises(ValueError, match="two ranges"):
        field_ranges([*REQUEST_MODELS, Clash])


def test_serve_refuses_a_bad_port():
    with pytest.raises(InputError, match="port"):
        serve.run(argparse.Namespace(host="127.0.0.1", port=70000, log_level="info"))


def test_require_api_key_can_be_called_directly(tmp_path):
    """Routes that save state call it as a plain function (service/routes/calibration.py)."""
    from service_fakes import settings_for

    from service.deps import require_api_key

    settings = settings_for(tmp_path)
    require_api_key(settings, "test-key")  # accepted: returns None, raises nothing
    with pytest.raises(AuthError) as missing:
        require_api_key(settings, None)
    assert missing.value.status == 401
    with pytest.raises(AuthError) as wrong:
        require_api_key(settings, "nope")
    assert wrong.value.status == 403


@pytest.mark.parametrize("value", ["nan", "inf"])
def test_a_time_limit_that_is_no_number_is_called_so(monkeypatch, capsys, value):
    """``BALLOON_JOB_TIME_LIMIT_S=nan`` was refused as "Input should be less than or equal
    to 86400": the limit is not a number at all (the hostile-input audit of the forty-first
    session), and the refusal says so, with the range."""
    import uvicorn

    from service.cli import main

    monkeypatch.setattr(uvicorn, "run", lambda *a, **k: pytest.fail("the server started"))
    monkeypatch.setenv("BALLOON_JOB_TIME_LIMIT_S", value)
    get_settings.cache_clear()
    try:
        assert main(["serve", "--port", "8011"]) == 2
    finally:
        get_settings.cache_clear()
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "finite number" in line and "0 < job_time_limit_s <= 86400" in line, line
