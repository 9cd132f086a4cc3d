"""The control API's routes (FastAPI): REST/JSON over the Device face (docs/control.md).

The routes are fieldtwin.control.routers' (one APIRouter per resource group, the
answers typed by fieldtwin.control.replies): each validates its request (the
schemas), hands one function to the simulation's thread (``Sim.call``) or reads
the snapshot it published, and answers with the result.  Errors are
JSON: ``{"error": "...", "field": "...", "allowed": "..."}``; 400 for a user's
mistake the plant names, 404 for an unknown device, input, fault or exchange,
409 for a request the plant's state refuses (a time already past, a busy Text
Block), 413 for a body over 64 KiB, 422 for a body that does not fit its schema,
503 while the simulation cannot take a command, 504 when it did not answer in time.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.middleware.cors import CORSMiddleware

from fieldtwin import __version__
from fieldtwin.control.dashboard import add_dashboard, add_docs
from fieldtwin.control.document import allowed_methods, bodyless, declare, routed
from fieldtwin.control.guards import BodyLimit, BrowserGate, TokenGate, origin_of
from fieldtwin.control.lane import FastLane
from fieldtwin.control.resources import Conflict, Control, NotFound
from fieldtwin.control.routers import GROUPS, LANE
from fieldtwin.control.routers.common import Hop
from fieldtwin.control.sim import CommandTimeout, Sim
from fieldtwin.control.stream import add_stream
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.inbox import InboxClosed, InboxFull

_TYPE_TAGS = {"bool", "int", "float", "str", "list", "dict", "none"}


def _field(loc: Sequence[object]) -> str:
    """``body.speed`` from pydantic's loc (a union's member tags left out)."""
    parts = [
        str(part)
        for part in loc
        if isinstance(part, int) or (str(part).isidentifier() and str(part) not in _TYPE_TAGS)
    ]
    return ".".join(parts) or "body"


# what a field allows, by the kind of error pydantic found (its ``ctx`` gives bounds)
_ALLOWS: dict[str, Callable[[dict[str, Any]], str]] = {
    "float_type": lambda ctx: "a number",
    "float_parsing": lambda ctx: "a number",
    "finite_number": lambda ctx: "a finite number",
    "int_type": lambda ctx: "a whole number",
    "int_from_float": lambda ctx: "a whole number",
    "int_parsing": lambda ctx: "a whole number",
    "bool_type": lambda ctx: "true or false",
    "string_type": lambda ctx: "a string",
    "dict_type": lambda ctx: "a JSON object",
    "model_type": lambda ctx: "a JSON object",
    "model_attributes_type": lambda ctx: "a JSON object",
    "list_type": lambda ctx: "a list",
    "literal_error": lambda ctx: str(ctx.get("expected", "")),
    "greater_than": lambda ctx: f"a value > {ctx.get('gt')}",
    "greater_than_equal": lambda ctx: f"a value >= {ctx.get('ge')}",
    "less_than": lambda ctx: f"a value < {ctx.get('lt')}",
    "less_than_equal": lambda ctx: f"a value <= {ctx.get('le')}",
    "string_too_long": lambda ctx: f"at most {ctx.get('max_length')} characters",
    "string_too_short": lambda ctx: f"at least {ctx.get('min_length')} characters",
    "too_long": lambda ctx: f"at most {ctx.get('max_length')} items",
    "too_short": lambda ctx: f"at least {ctx.get('min_length')} items",
    "missing": lambda ctx: "a value (the field is required)",
    "extra_forbidden": lambda ctx: "no such field (GET /openapi.json lists the route's fields)",
    "json_invalid": lambda ctx: "a JSON body",
}


def _allows(error: Mapping[str, Any]) -> str:
    """What the field allows, said plainly; pydantic's own words where it has no phrase."""
    phrase = _ALLOWS.get(str(error.get("type", "")))
    ctx = error.get("ctx")
    if phrase is not None:
        return phrase(ctx if isinstance(ctx, dict) else {})
    said = str(ctx["error"]) if isinstance(ctx, dict) and "error" in ctx else str(error["msg"])
    return said.removeprefix("Value error, ").removeprefix("Input should be ")


def _refused(field: str, error: Mapping[str, Any]) -> str:
    """What was wrong: the value refused (shortened), or the field missing."""
    if error.get("type") == "missing":
        return f"{field}: required"
    if "input" not in error:
        return f"{field}: {error.get('msg', 'invalid')}"
    shown = json.dumps(error["input"], default=str)
    shown = shown if len(shown) <= 60 else shown[:57] + "..."
    return f"{field}: {shown} is not allowed"


def _validation(request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, RequestValidationError)
    problems: dict[str, list[str]] = {}
    allows: dict[str, list[str]] = {}
    first: dict[str, str] = {}
    for error in exc.errors()[:20]:
        where = _field(error.get("loc", ()))
        problems.setdefault(where, []).append(str(error.get("msg", "")))
        allows.setdefault(where, []).append(_allows(error))
        first.setdefault(where, _refused(where, error))
    field = next(iter(problems), "body")
    allowed = " or ".join(dict.fromkeys(allows.get(field, ["a valid body"])))
    return JSONResponse(
        status_code=422,
        content={
            "error": first.get(field, f"{field}: invalid"),
            "field": field,
            "allowed": allowed,
            "problems": [{"field": f, "problem": " or ".join(t)} for f, t in problems.items()],
        },
    )


def _http_error(request: Request, exc: Exception) -> JSONResponse:
    assert isinstance(exc, StarletteHTTPException)
    body = {"error": str(exc.detail)}
    if "body" in str(exc.detail):
        body["field"] = "body"
    headers = exc.headers
    if exc.status_code == 405:  # every method of the path, not only the first route's
        allow = ", ".join(allowed_methods(request.app, request.scope))
        body["allowed"] = allow
        headers = {**(headers or {}), "Allow": allow}
    return JSONResponse(status_code=exc.status_code, content=body, headers=headers)


def _plant_error(request: Request, exc: Exception) -> JSONResponse:
    status = 404 if isinstance(exc, NotFound) else 409 if isinstance(exc, Conflict) else 400
    return JSONResponse(status_code=status, content={"error": str(exc)})


def _busy(request: Request, exc: Exception) -> JSONResponse:
    return JSONResponse(status_code=503, content={"error": str(exc)})


def _late(request: Request, exc: Exception) -> JSONResponse:
    return JSONResponse(status_code=504, content={"error": str(exc)})


def create_app(
    control: Control,
    sim: Sim,
    *,
    token: str | None = None,
    host: str | None = None,
    allow_origins: Sequence[str] = (),
    lane: bool = True,
) -> Any:
    """The ASGI application: the routes inside the token gate, the browser's doors
    (Host, Origin, JSON bodies: ``host`` is the configured listening host) and the
    body limit (fieldtwin.control.guards); in front, the fast lane of the hot command
    routes (fieldtwin.control.lane; ``lane=False``: without it)."""
    app = FastAPI(
        docs_url=None,
        redoc_url=None,
        title="fieldtwin control API",
        version=__version__,
        description="A running fieldtwin plant: devices, inputs, faults, objects, Text Blocks,"
        " power, the clock, the console and the event stream (docs/control.md).",
    )
    app.add_exception_handler(RequestValidationError, _validation)
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(ConfigError, _plant_error)
    app.add_exception_handler(InboxFull, _busy)
    app.add_exception_handler(InboxClosed, _busy)
    app.add_exception_handler(CommandTimeout, _late)

    hop = Hop(control, sim)
    for group in GROUPS:
        # each group's routes become the app's own (their paths are whole): the gates,
        # the 405's Allow and the document find a route by path and method among
        # app.router.routes (fieldtwin.control.document), which include_router would
        # hide behind one entry per router
        app.router.routes.extend(group.router(hop).routes)
    add_stream(app, control, sim)
    add_dashboard(app)
    add_docs(app)
    declare(app, token=token is not None)
    gate = TokenGate(app, token)
    inner: Any = gate
    origins = [o for o in map(origin_of, allow_origins) if o]
    if origins:  # a page of an allowed origin may call the API (its preflights answered)
        inner = CORSMiddleware(
            inner,
            allow_origins=origins,
            allow_methods=["GET", "POST", "PUT", "DELETE"],
            allow_headers=["authorization", "content-type"],
        )
    doors = BrowserGate(
        inner, host=host, allow_origins=origins, bodyless=bodyless(app), routed=routed(app)
    )
    gated = BodyLimit(doors)
    if not lane:
        return gated
    return FastLane(gated, app, hop, LANE, doors=doors, token=gate)


__all__ = ["create_app"]
