"""The dashboard (docs/dashboard.md): the page at ``/``, its files, and its one look.

``GET /`` is the page, rendered from the Jinja2 template ``templates/dashboard.html``;
``/static/...`` its scripts, styles and the vendored uPlot (every file ships in
the package: no CDN); ``GET /docs`` the API's document in Swagger UI, vendored too.
``GET /dashboard/state`` (fieldtwin.control.routers.dashboard) gives, in one
answer, what the page draws (fieldtwin.control.panels), from the snapshot the
simulation published like every other read: the page never touches the
simulation, and everything it changes goes through the control API's own resources.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles

from fieldtwin import __version__

HERE = Path(__file__).resolve().parent
STATIC = HERE / "static"
TEMPLATES = HERE / "templates"
MIN_RATE, MAX_RATE, DEFAULT_RATE = 1, 20, 5  # updates per second the page asks for


def _rate(text: str | None) -> int:
    try:
        value = int(text or DEFAULT_RATE)
    except ValueError:
        return DEFAULT_RATE
    return max(MIN_RATE, min(MAX_RATE, value))


def add_dashboard(app: FastAPI) -> None:
    templates: list[Any] = []  # Jinja2 loaded at the first page (not at `fieldtwin run`'s start)

    def template() -> Any:
        if not templates:
            from fastapi.templating import Jinja2Templates

            templates.append(Jinja2Templates(directory=str(TEMPLATES)))
        return templates[0]

    app.mount("/static", StaticFiles(directory=str(STATIC)), name="static")

    @app.get("/", include_in_schema=False, response_class=HTMLResponse)
    async def page(request: Request) -> Any:
        # the token, if any, came in the URL once and is kept in a cookie (control.guards):
        # the page and its files never carry it
        return template().TemplateResponse(
            request,
            "dashboard.html",
            {
                "version": __version__,
                "suffix": f"?v={__version__}",
                "rate": _rate(request.query_params.get("rate")),
            },
        )


def add_docs(app: FastAPI) -> None:
    """``GET /docs``: Swagger UI over ``/openapi.json``, from the package's own files."""
    from fastapi.openapi.docs import get_swagger_ui_html

    vendor = "/static/vendor/swagger-ui"

    @app.get("/docs", include_in_schema=False, response_class=HTMLResponse)
    async def docs() -> Any:
        return get_swagger_ui_html(
            openapi_url="/openapi.json",
            title=f"{app.title} {__version__}",
            swagger_js_url=f"{vendor}/swagger-ui-bundle.js?v={__version__}",
            swagger_css_url=f"{vendor}/swagger-ui.css?v={__version__}",
            swagger_favicon_url=f"{vendor}/favicon-32x32.png",
            # no badge fetched from the validator's site: nothing leaves the machine
            swagger_ui_parameters={"validatorUrl": None},
        )


__all__ = ["DEFAULT_RATE", "MAX_RATE", "add_dashboard", "add_docs"]
