"""Pages for people: the design explorer at ``/``, Swagger UI at ``/docs``, Redoc at
``/redoc``, and their files under ``/static``.

Everything a page loads ships in the package (``service/static``; the vendored Swagger UI
and Redoc come from the npm registry, see ``service/static/vendor/README.md``), so the
pages work on a lab PC with no internet. The explorer talks only to the ``/v1`` API.
"""

from __future__ import annotations

from pathlib import Path

from fastapi import APIRouter, FastAPI
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.responses import FileResponse, HTMLResponse
from fastapi.staticfiles import StaticFiles

STATIC_DIR = Path(__file__).resolve().parent.parent / "static"
STATIC_URL = "/static"
FAVICON_URL = f"{STATIC_URL}/explorer/favicon.svg"
# Swagger UI asks validator.swagger.io about the schema unless told not to.
SWAGGER_PARAMETERS = {"validatorUrl": None, "deepLinking": True, "showExtensions": True,
                      "showCommonExtensions": True}

router = APIRouter(include_in_schema=False)


@router.get("/", response_class=FileResponse)
def explorer() -> FileResponse:
    """The design explorer (plain HTML, CSS and JavaScript; no build step)."""
    return FileResponse(STATIC_DIR / "explorer" / "index.html", media_type="text/html")


@router.get("/docs", response_class=HTMLResponse)
def swagger_ui() -> HTMLResponse:
    return get_swagger_ui_html(
        openapi_url="/openapi.json", title="Balloon actuator design service - API",
        swagger_js_url=f"{STATIC_URL}/vendor/swagger-ui/swagger-ui-bundle.js",
        swagger_css_url=f"{STATIC_URL}/vendor/swagger-ui/swagger-ui.css",
        swagger_favicon_url=FAVICON_URL, swagger_ui_parameters=SWAGGER_PARAMETERS)


@router.get("/redoc", response_class=HTMLResponse)
def redoc() -> HTMLResponse:
    return get_redoc_html(
        openapi_url="/openapi.json", title="Balloon actuator design service - API",
        redoc_js_url=f"{STATIC_URL}/vendor/redoc/redoc.standalone.js",
        redoc_favicon_url=FAVICON_URL, with_google_fonts=False)


def install_pages(app: FastAPI) -> None:
    """Add the pages and mount the static files (the app is built with docs_url=None)."""
    app.include_router(router)
    app.mount(STATIC_URL, StaticFiles(directory=STATIC_DIR), name="static")
