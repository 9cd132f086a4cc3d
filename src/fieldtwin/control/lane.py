"""A fast lane for the hot routes, in front of the gates and FastAPI's router.

``PUT /devices/{ident}/inputs/{name}`` and ``PUT /devices/{ident}/objects/{name}``
(an input, a PL7 object or a TES register) are what a test or an HMI sends in a
loop, and ``GET /clock`` what it polls.  Through the whole stack a request passes
three gates (fieldtwin.control.guards), FastAPI's middleware, router, dependency
solving and two validations: about 0.6 ms of CPU for a command whose own work is a
few tens of microseconds (docs/performance.md, "The control API's PUT: a lane and
turns").  The lane answers the *happy path* of those routes by itself, and only it:
a request the gates would pass unchanged, a path whose route is one of the lane's
(the very route the router would pick), a JSON body the route's own model takes (a
read: no body declared).  Everything else - no or a wrong token, a Host, Origin or
Sec-Fetch-Site header, another Content-Type, a body over the bound or one that does
not fit, an unknown path - falls through, with the body it read handed on unchanged,
to the whole stack, which stays the documented and reference route (the OpenAPI
document is the routers').

On the lane a command is the same value through the same door (``Sim.command``:
the inbox, the runner's one dispatcher, the recording, the snapshot made stale
before the answer), and a read the same ``Hop.read`` of the snapshot
(read-your-writes: a read sent after a command's answer sees its effect); the
answer is the route's own reply model serialized by the route's own response field
(FastAPI's ``exclude_unset``), with the security headers the gates add; an error
the command or the read raises gets the app's own exception handler (404, 409, 400,
503, 504), as through the router.  tests/control/test_lane.py sends the same random
requests to an app with the lane and one without and finds the same answers and
the same recorded commands.
"""

from __future__ import annotations

import inspect
import secrets
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from fastapi import FastAPI
from fastapi.routing import APIRoute
from pydantic import BaseModel, TypeAdapter, ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.requests import Request
from starlette.routing import Match
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from fieldtwin.control.guards import MAX_BODY, SECURITY_HEADERS, BrowserGate, TokenGate
from fieldtwin.control.sim import Sim

if TYPE_CHECKING:
    from fieldtwin.control.resources import Control
    from fieldtwin.control.routers.common import Hop

PATHS_KEPT = 1024  # paths whose route the lane remembers; then forgotten (bounded)
HOSTS_KEPT = 64  # Host headers whose verdict the lane remembers; then forgotten (bounded)
ANSWERS_KEPT = 256  # answers written, remembered per route; then forgotten (bounded)
_PLAIN = frozenset({str, bool, int})  # the value types whose JSON their type and == fix
JSON_TYPES = frozenset({b"application/json", b"application/json; charset=utf-8"})
Call = tuple[str, tuple[object, ...]]


B = TypeVar("B", bound=BaseModel)
R = TypeVar("R", bound=BaseModel)


@dataclass(frozen=True)
class LaneRoute(Generic[B, R]):
    """One route the lane may answer: its method and path as the router declares them,
    its body's model, the command it runs (from the path's parameters and the body) and
    the model of the route's answer (the command's answer validated into it).  The
    router's endpoint uses the same ``call`` and ``reply``, and the route must declare
    ``reply`` as its response model: the two ways cannot drift apart."""

    method: str
    path: str
    body: type[B]
    call: Callable[[Mapping[str, Any], B], Call]
    reply: type[R]

    def answer(self, value: Any) -> R:
        """The route's answer: the command's validated into the reply model."""
        return self.reply.model_validate(value)


@dataclass(frozen=True)
class LaneRead(Generic[R]):
    """A read the lane may answer, from the snapshot the simulation published: its path
    as the router declares it (a GET), the snapshot's key and the reading function for
    the path's parameters (``Hop.read``'s two arguments), and the model of the route's
    answer.  The router's endpoint uses the same ``read`` and ``reply``."""

    path: str
    read: Callable[[Control, Mapping[str, Any]], tuple[Hashable, Callable[[], Any]]]
    reply: type[R]
    method: str = "GET"

    def answer(self, value: Any) -> R:
        """The route's answer: the reading validated into the reply model."""
        return self.reply.model_validate(value)


@dataclass(frozen=True)
class _Way:
    """A lane route bound to the app's route of the same path and method."""

    lane: LaneRoute[Any, Any] | LaneRead[Any]
    route: APIRoute
    body: TypeAdapter[Any] | None  # the body's model (None: a read, no body)
    # answers as the route writes them, by their _plain key (bounded: ANSWERS_KEPT)
    written: dict[tuple[object, ...], bytes] = field(default_factory=dict)


_NONE = object()  # a path remembered as not the lane's


class FastLane:
    """ASGI: the lane's routes answered here on their happy path; every other request,
    and any doubt, goes to ``app`` (the gates around FastAPI) as it came."""

    def __init__(
        self,
        app: ASGIApp,
        api: FastAPI,
        hop: Hop,
        routes: Sequence[LaneRoute[Any, Any] | LaneRead[Any]],
        *,
        doors: BrowserGate,
        token: TokenGate,
    ) -> None:
        self.app = app
        self.api = api
        self.hop = hop
        self.sim: Sim = hop.sim
        self.doors = doors
        self.token = token
        self._ways: dict[int, _Way] = {}  # by id of the app's route
        for lane in routes:
            route = _route(api, lane)
            body = TypeAdapter(lane.body) if isinstance(lane, LaneRoute) else None
            self._ways[id(route)] = _Way(lane, route, body)
        self.methods = frozenset(lane.method for lane in routes)
        # (the route's way, its path parameters) by (method, root path, path), or _NONE
        self._paths: dict[tuple[str, str, str], tuple[_Way, dict[str, Any]] | object] = {}
        self._hosts: dict[bytes, bool] = {}  # BrowserGate.host_ok by Host header
        self.answered = 0  # requests the lane answered (the rest fell through)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] not in self.methods:
            await self.app(scope, receive, send)
            return
        found = self._way(scope)
        if found is _NONE:
            await self.app(scope, receive, send)
            return
        assert isinstance(found, tuple)
        way, params = found
        if not self._admitted(scope, way.body is not None):
            await self.app(scope, receive, send)
            return
        lane = way.lane
        try:
            if isinstance(lane, LaneRead):
                self.answered += 1
                answer = await self.hop.read(*lane.read(self.hop.control, params))
            else:
                assert way.body is not None
                read: list[Message] = []
                body = await _body(receive, read)
                model = None
                if body is not None:
                    try:
                        model = way.body.validate_json(body)
                    except ValidationError:
                        model = None
                if model is None:  # over the bound, cut short, or not the route's body
                    await self.app(scope, _replay(read, receive), send)
                    return
                self.answered += 1
                name, args = lane.call(params, model)
                answer = await self.sim.command(name, *args)
            # the route's response field validates the answer into the reply model and
            # writes it (one validation, where the endpoint's model_validate and
            # FastAPI's serialize_response make two of the same); an answer of plain
            # strings, booleans and whole numbers is written once and remembered
            key = _plain(answer)
            data = way.written.get(key) if key is not None else None
            if data is None:
                data = _serialized(way.route, answer)
                if key is not None:
                    if len(way.written) >= ANSWERS_KEPT:
                        way.written.clear()
                    way.written[key] = data
        except Exception as exc:
            handler = _handler(self.api, exc)
            if handler is None:
                raise
            response = handler(Request(scope, receive), exc)
            if inspect.isawaitable(response):
                response = await response
            await response(scope, receive, _secured(send))
            return
        status = way.route.status_code or 200
        await send(
            {
                "type": "http.response.start",
                "status": status,
                "headers": [
                    (b"content-length", str(len(data)).encode()),
                    (b"content-type", b"application/json"),
                    *SECURITY_HEADERS,
                ],
            }
        )
        await send({"type": "http.response.body", "body": data})

    def _way(self, scope: Scope) -> tuple[_Way, dict[str, Any]] | object:
        """The lane's way for this request if the router would take it to one of the
        lane's routes (the first route that fully matches, as Starlette's router picks)."""
        key = (scope["method"], scope.get("root_path", ""), scope["path"])
        found = self._paths.get(key)
        if found is None:
            found = _NONE
            for route in self.api.router.routes:
                match, child = route.matches(scope)
                if match is Match.FULL:
                    way = self._ways.get(id(route))
                    if way is not None:
                        found = (way, dict(child.get("path_params", {})))
                    break
            if len(self._paths) >= PATHS_KEPT:
                self._paths.clear()
            self._paths[key] = found
        return found

    def _admitted(self, scope: Scope, body: bool) -> bool:
        """The gates would let this request through unchanged: every header they look
        at given once, the Host this plant's, no Origin nor Sec-Fetch-Site (a browser's
        request: the whole stack judges it, CORS included), and the token when one is
        set; with a ``body``, a JSON Content-Type and a declared length within the
        bound; without (a read), no body declared at all."""
        raw = scope["headers"]
        headers: dict[bytes, bytes] = dict(raw)
        if len(headers) != len(raw):
            return False  # a header given twice: let the gates judge it
        host = headers.get(b"host")
        if host is None:
            return False
        known = self._hosts.get(host)
        if known is None:  # the gate's answer for this Host, remembered (bounded)
            known = self.doors.host_ok(host.decode("latin-1"))
            if len(self._hosts) >= HOSTS_KEPT:
                self._hosts.clear()
            self._hosts[host] = known
        if not known:
            return False
        if b"origin" in headers or b"sec-fetch-site" in headers:
            return False
        if not body:
            if b"content-length" in headers or b"transfer-encoding" in headers:
                return False
            return self._token_ok(scope)
        kind = headers.get(b"content-type")
        if kind is None or kind.strip().lower() not in JSON_TYPES:
            return False
        length = headers.get(b"content-length")
        if length is not None and not (length.isdigit() and int(length) <= MAX_BODY):
            return False
        return self._token_ok(scope)

    def _token_ok(self, scope: Scope) -> bool:
        """No token set, or the right one given by header or cookie (TokenGate's way)."""
        if self.token.token is None:
            return True
        given, keep = self.token.given(scope)
        return (
            given is not None
            and not keep
            and secrets.compare_digest(given.encode(), self.token.token.encode())
        )


def _route(api: FastAPI, lane: LaneRoute[Any, Any] | LaneRead[Any]) -> APIRoute:
    for route in api.router.routes:
        if (
            isinstance(route, APIRoute)
            and route.path_format == lane.path
            and lane.method in (route.methods or ())
        ):
            if route.response_model is not lane.reply:
                raise ValueError(
                    f"{lane.method} {lane.path} answers {route.response_model!r}, the fast"
                    f" lane {lane.reply!r}: they must be the same model"
                )
            return route
    raise ValueError(f"no route {lane.method} {lane.path} for the fast lane")


async def _body(receive: Receive, read: list[Message]) -> bytes | None:
    """The whole body, each message kept in ``read``; None when the connection ended
    first or the body passed the bound (the stack says what then)."""
    chunks: list[bytes] = []
    size = 0
    while True:
        message = await receive()
        read.append(message)
        if message["type"] != "http.request":
            return None
        chunk = message.get("body", b"")
        size += len(chunk)
        if size > MAX_BODY:
            return None
        chunks.append(chunk)
        if not message.get("more_body", False):
            return b"".join(chunks)


def _replay(read: list[Message], then: Receive) -> Receive:
    """What the lane read, message by message, then what the connection says."""
    pending = list(read)

    async def receive() -> Message:
        if pending:
            return pending.pop(0)
        return await then()

    return receive


def _plain(answer: Any) -> tuple[object, ...] | None:
    """A key that fixes ``answer``'s JSON (its keys in order, each value's type and value)
    when it is a dict of strings, booleans and whole numbers; else None.  Equal keys
    give the same body: ``True``, ``1`` and ``1.0`` differ by type, and a float (``-0.0``
    equals ``0.0``) or a container is never keyed."""
    if type(answer) is not dict:
        return None
    values = tuple(answer.values())
    types = tuple(map(type, values))
    if not _PLAIN.issuperset(types):
        return None
    return (tuple(answer), types, values)


def _serialized(route: APIRoute, content: Any) -> bytes:
    """The answer as the route's response field writes it (FastAPI's serialize_response:
    validated into the model, then dumped with the route's options)."""
    field = route.response_field
    assert field is not None
    value, errors = field.validate(content, {}, loc=("response",))
    if errors:
        raise ValueError(f"the answer does not fit {route.path}'s model: {errors}")
    data: bytes = field.serialize_json(
        value,
        include=route.response_model_include,
        exclude=route.response_model_exclude,
        by_alias=route.response_model_by_alias,
        exclude_unset=route.response_model_exclude_unset,
        exclude_defaults=route.response_model_exclude_defaults,
        exclude_none=route.response_model_exclude_none,
    )
    return data


def _handler(api: FastAPI, exc: Exception) -> Callable[[Request, Exception], Any] | None:
    """The app's handler of this exception (by its class's MRO, as Starlette looks)."""
    if isinstance(exc, StarletteHTTPException):
        return None
    for kind in type(exc).__mro__:
        handler = api.exception_handlers.get(kind)
        if handler is not None:
            return handler
    return None


def _secured(send: Send) -> Send:
    async def secured(message: Message) -> None:
        if message["type"] == "http.response.start":
            message = {**message, "headers": [*message.get("headers", []), *SECURITY_HEADERS]}
        await send(message)

    return secured


__all__ = ["Call", "FastLane", "LaneRead", "LaneRoute"]
