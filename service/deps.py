"""Request dependencies as ``Annotated`` aliases (swap them with ``app.dependency_overrides``).

The read-path ones are ``async def`` although they never await: FastAPI runs a plain
``def`` dependency in its thread pool, a hand-off that costs more than the predict
itself. ``require_api_key`` stays a plain function: other routes call it directly.
"""

from __future__ import annotations

import hmac
from typing import Annotated

from fastapi import Depends, Request, Security
from fastapi.security import APIKeyHeader

from service.errors import AuthError
from service.jobs import JobManager
from service.models import ModelRegistry
from service.settings import ServiceSettings

API_KEY_HEADER = APIKeyHeader(name="X-API-Key", auto_error=False,
                              description="required by the mutating endpoints")


async def app_settings(request: Request) -> ServiceSettings:
    return request.app.state.settings


async def app_models(request: Request) -> ModelRegistry:
    return request.app.state.models


async def app_jobs(request: Request) -> JobManager:
    return request.app.state.jobs


SettingsDep = Annotated[ServiceSettings, Depends(app_settings)]
ModelsDep = Annotated[ModelRegistry, Depends(app_models)]
JobsDep = Annotated[JobManager, Depends(app_jobs)]


def require_api_key(settings: SettingsDep,
                    key: Annotated[str | None, Security(API_KEY_HEADER)] = None) -> None:
    """Mutating endpoints: 401 without a key, 403 with a wrong one or when none is set."""
    if settings.api_key is None:
        raise AuthError("mutating endpoints are disabled: the server has no API key "
                        "(set BALLOON_API_KEY)", status=403)
    if not key:
        raise AuthError("this endpoint needs an API key in the X-API-Key header")
    if not hmac.compare_digest(key.encode(), settings.api_key.get_secret_value().encode()):
        raise AuthError("the API key is not valid", status=403)


ApiKeyDep = Depends(require_api_key)
