"""The OpenAPI document is the API: what each route can answer, as it answers it.

FastAPI writes the request schemas and the success answers; this module adds
what the gates and the error handlers answer (fieldtwin.control.guards, app):
every status code a route can give, with the API's own error body (not
FastAPI's ``{"detail": ...}``), and the ``{}`` body that a state-changing route
without a value takes.  It also gives the routes' ``Allow`` list for a 405, the
same as the document's methods for that path (RFC 9110).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from fastapi import FastAPI
from fastapi.routing import APIRoute
from starlette.routing import Match
from starlette.types import Scope

from fieldtwin.control.guards import STATE_CHANGING

ERROR_SCHEMA: dict[str, Any] = {
    "type": "object",
    "required": ["error"],
    "properties": {
        "error": {"type": "string", "description": "what is wrong, and what is allowed"},
        "field": {"type": "string", "description": "the field, header or parameter at fault"},
        "allowed": {"type": "string"},
        "problems": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["field", "problem"],
                "properties": {"field": {"type": "string"}, "problem": {"type": "string"}},
            },
        },
    },
}
EMPTY_BODY_SCHEMA: dict[str, Any] = {
    "type": "object",
    "maxProperties": 0,
    "additionalProperties": False,
    "description": "this route takes no value: send {} (a JSON body, which an HTML form cannot)",
}
NAMED_IN_BODY = frozenset({"/plc/remove", "/plc/insert"})  # a module slot: 404 if empty
CONFLICTS = frozenset({"/clock/run-until", "/exchanges", "/tags/{name}"})  # refused: 409
WHY = {
    400: "the plant refuses (a value it does not take, a busy Text Block, a body not UTF-8)"
    ", or a Host header that is not this plant's",
    401: "a token is required and missing or wrong",
    403: "a request from another origin or site (Origin, Sec-Fetch-Site)",
    404: "an unknown device, input, fault, object, exchange or module slot",
    409: "the plant's state refuses it: a time already past, a busy Text Block, a table"
    " shorter than its length",
    413: "a body over 64 KiB",
    415: "a request that changes the plant without Content-Type: application/json",
    422: "the body or a parameter does not fit its schema",
    503: "the simulation cannot take a command now (256 waiting, or stopping)",
    504: "the simulation did not finish the command in time (its effect stands)",
}


def route_for(app: FastAPI, scope: Scope) -> APIRoute | None:
    """The API route that takes this request (path and method), if any."""
    for route in app.router.routes:
        if isinstance(route, APIRoute) and route.matches(scope)[0] is Match.FULL:
            return route
    return None


def routed(app: FastAPI) -> Callable[[Scope], bool]:
    return lambda scope: route_for(app, scope) is not None


def bodyless(app: FastAPI) -> Callable[[Scope], bool]:
    def check(scope: Scope) -> bool:
        route = route_for(app, scope)
        return route is not None and route.body_field is None

    return check


def allowed_methods(app: FastAPI, scope: Scope) -> list[str]:
    """Every method some route takes at this path (a 405's ``Allow``)."""
    methods: set[str] = set()
    for route in app.router.routes:
        if isinstance(route, APIRoute) and route.matches(scope)[0] is not Match.NONE:
            methods |= route.methods or set()
    return sorted(methods)


def _codes(route: APIRoute, method: str, token: bool) -> list[int]:
    codes = [400, 403, 503, 504]
    if token:
        codes.append(401)
    if route.dependant.path_params or route.path_format in NAMED_IN_BODY:
        codes.append(404)
    if route.path_format in CONFLICTS:
        codes.append(409)
    if route.dependant.path_params or route.dependant.query_params:
        codes.append(422)
    if method in STATE_CHANGING:
        codes += [413, 415, 422]
    return sorted(set(codes))


def declare(app: FastAPI, *, token: bool) -> None:
    """Complete ``app``'s OpenAPI document (generated once, at its first request)."""
    generate = app.openapi

    def document() -> dict[str, Any]:
        if app.openapi_schema is not None:
            return app.openapi_schema
        schema: dict[str, Any] = generate()
        routes = {
            (route.path_format, method): route
            for route in app.router.routes
            if isinstance(route, APIRoute)
            for method in route.methods or ()
        }
        for path, operations in schema.get("paths", {}).items():
            for method, operation in operations.items():
                route = routes.get((path, method.upper()))
                if route is None:
                    continue
                if method.upper() in STATE_CHANGING and "requestBody" not in operation:
                    operation["requestBody"] = {
                        "required": True,
                        "content": {"application/json": {"schema": EMPTY_BODY_SCHEMA}},
                    }
                responses = operation.setdefault("responses", {})
                for code in _codes(route, method.upper(), token):
                    responses[str(code)] = {
                        "description": WHY[code],
                        "content": {"application/json": {"schema": ERROR_SCHEMA}},
                    }
        components = schema.get("components", {}).get("schemas", {})
        for unused in ("HTTPValidationError", "ValidationError"):
            components.pop(unused, None)
        return schema

    app.openapi = document  # type: ignore[method-assign]


__all__ = ["allowed_methods", "bodyless", "declare", "route_for", "routed"]
