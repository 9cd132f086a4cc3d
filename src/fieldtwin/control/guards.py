"""The control API's gates, as ASGI middleware: the body bound, the browser's doors, the token.

* ``BodyLimit``: a request body over ``max_bytes`` (64 KiB) gets 413 as soon as
  its Content-Length says so, or as soon as the bytes received pass the bound
  (chunked bodies): it is never read whole (DESIGN rule 14).
* ``TokenGate``: when a token is set (always when the API is reachable from
  other machines) every request and WebSocket must give it: ``Authorization:
  Bearer TOKEN``, or the HttpOnly SameSite=Strict cookie the dashboard's first
  page load sets; ``?token=TOKEN`` only on the WebSocket and on that first page
  load (``GET /``), never on other routes (it would land in URLs and history).
  401 without it.
* ``BrowserGate``: what a web page the plant was not given cannot do
  (docs/control.md, "Security model"): a ``Host`` that is not a loopback name
  or the configured host gets 400 (DNS rebinding); a state-changing request or
  a WebSocket whose ``Origin`` is another origin (not allowed by
  ``--allow-origin``) gets 403, as does any other request a browser marks as
  coming from another site (``Sec-Fetch-Site``) except a top-level navigation
  to the page; a state-changing request without ``Content-Type:
  application/json`` (which an HTML form cannot send) gets 415, and a route
  that takes no body takes ``{}``.
"""

from __future__ import annotations

import ipaddress
import json
import secrets
from collections.abc import Callable, Sequence
from urllib.parse import parse_qs, quote, unquote, urlsplit

from starlette.types import ASGIApp, Message, Receive, Scope, Send

MAX_BODY = 64 * 1024
COOKIE = "fieldtwin_token"  # + _PORT: the dashboard's token, kept after its first load


class BodyTooLarge(Exception):
    pass


async def _json(send: Send, status: int, body: dict[str, object]) -> None:
    data = json.dumps(body).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(data)).encode()),
                (b"connection", b"close"),
            ],
        }
    )
    await send({"type": "http.response.body", "body": data})


class BodyLimit:
    def __init__(self, app: ASGIApp, max_bytes: int = MAX_BODY) -> None:
        self.app = app
        self.max_bytes = max_bytes

    def _too_large(self) -> dict[str, object]:
        return {
            "error": f"request body too large (allowed up to {self.max_bytes} bytes)",
            "field": "body",
        }

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        for key, value in scope.get("headers", []):
            if key == b"content-length":
                try:
                    declared = int(value)
                except ValueError:
                    declared = self.max_bytes + 1
                if declared > self.max_bytes:
                    await _json(send, 413, self._too_large())
                    return
        seen = 0
        started = False

        async def bounded() -> Message:
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.max_bytes:
                    raise BodyTooLarge
            return message

        async def watch(message: Message) -> None:
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, bounded, watch)
        except BodyTooLarge:
            if not started:
                await _json(send, 413, self._too_large())


class TokenGate:
    def __init__(self, app: ASGIApp, token: str | None) -> None:
        self.app = app
        self.token = token

    @staticmethod
    def cookie_name(scope: Scope) -> str:
        """One cookie per port: cookies are shared by every port of a host."""
        server = scope.get("server") or ("", 0)
        return f"{COOKIE}_{server[1]}"

    def given(self, scope: Scope) -> tuple[str | None, bool]:
        """The token given, and whether it came in the URL of the page (to be kept)."""
        cookie_name = self.cookie_name(scope).encode()
        for key, value in scope.get("headers", []):
            if key == b"authorization":
                text = bytes(value).decode("latin-1")
                if text.lower().startswith("bearer "):
                    return text[7:].strip(), False
        for key, value in scope.get("headers", []):
            if key == b"cookie":
                for part in bytes(value).split(b";"):
                    name, _, given = part.strip().partition(b"=")
                    if name == cookie_name:
                        return unquote(given.decode("latin-1")), False
        page = scope["type"] == "http" and scope.get("path") == "/"
        if scope["type"] == "websocket" or page:
            raw: bytes = scope.get("query_string", b"")
            tokens = parse_qs(raw.decode("latin-1")).get("token", [])
            if tokens:
                return tokens[0], page
        return None, False

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if self.token is None or scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        given, keep = self.given(scope)
        if given is not None and secrets.compare_digest(given.encode(), self.token.encode()):
            if not keep:
                await self.app(scope, receive, send)
                return
            cookie = (
                f"{self.cookie_name(scope)}={quote(self.token, safe='')};"
                " HttpOnly; SameSite=Strict; Path=/"
            )

            async def keep_it(message: Message) -> None:
                if message["type"] == "http.response.start":
                    headers = [*message.get("headers", []), (b"set-cookie", cookie.encode())]
                    message = {**message, "headers": headers}
                await send(message)

            await self.app(scope, receive, keep_it)
            return
        if scope["type"] == "websocket":
            await send({"type": "websocket.close", "code": 1008, "reason": "token required"})
            return
        await _json(
            send,
            401,
            {"error": "a token is required (Authorization: Bearer TOKEN)", "field": "token"},
        )


STATE_CHANGING = frozenset({"POST", "PUT", "DELETE", "PATCH"})
LOOPBACK_NAMES = frozenset({"localhost", "127.0.0.1", "::1"})
ROUTE_KINDS = 1024  # (method, path) pairs remembered by BrowserGate; then forgotten
NAVIGATION_PAGES = frozenset({"/", "/docs"})  # what another site may link to (GET only)
SECURITY_HEADERS = [
    (b"x-frame-options", b"DENY"),  # no page may frame the dashboard (clickjacking)
    (b"content-security-policy", b"frame-ancestors 'none'"),
    (b"x-content-type-options", b"nosniff"),
]


def _host_name(host: str) -> str:
    """``[::1]:8520`` -> ``::1``; ``LocalHost:80`` -> ``localhost``."""
    host = host.strip().lower()
    if host.startswith("["):
        return host[1 : host.find("]")] if "]" in host else host
    if host.count(":") == 1:
        host = host.partition(":")[0]
    return host.rstrip(".")


def loopback_host(name: str) -> bool:
    if name in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


def origin_of(text: str) -> str | None:
    """``http://Host:80/`` -> ``http://host``: the origin as compared; None if not one."""
    try:
        parts = urlsplit(text.strip())
        port = parts.port
    except ValueError:
        return None
    if parts.scheme not in ("http", "https") or not parts.hostname:
        return None
    if parts.path not in ("", "/") or parts.query or parts.fragment or parts.username:
        return None
    host = parts.hostname.lower()
    shown = f"[{host}]" if ":" in host else host
    default = 80 if parts.scheme == "http" else 443
    return f"{parts.scheme}://{shown}" + ("" if port in (None, default) else f":{port}")


class BrowserGate:
    """The doors a browser would use: Host, Origin, Sec-Fetch-Site and the JSON body."""

    def __init__(
        self,
        app: ASGIApp,
        *,
        host: str | None = None,
        allow_origins: Sequence[str] = (),
        bodyless: Callable[[Scope], bool] | None = None,
        routed: Callable[[Scope], bool] | None = None,
    ) -> None:
        self.app = app
        self.host = None if host is None else _host_name(host)
        self.any_host = self.host is not None and self.host in ("0.0.0.0", "::", "")
        self.allow_origins = frozenset(o for o in map(origin_of, allow_origins) if o)
        self.bodyless = bodyless or (lambda scope: False)
        self.routed = routed or (lambda scope: True)
        # (routed, bodyless) by method and path: the routes are fixed once served, and a
        # lookup tries every route's pattern (bounded: cleared when full)
        self._kinds: dict[tuple[str, str, str], tuple[bool, bool]] = {}

    def _kind(self, scope: Scope, method: str) -> tuple[bool, bool]:
        """Whether a route takes this request, and whether that route takes no body."""
        key = (method, str(scope.get("root_path", "")), str(scope.get("path", "")))
        found = self._kinds.get(key)
        if found is None:
            routed = self.routed(scope)
            found = (routed, routed and self.bodyless(scope))
            if len(self._kinds) >= ROUTE_KINDS:
                self._kinds.clear()
            self._kinds[key] = found
        return found

    def host_ok(self, host: str | None) -> bool:
        if self.any_host:  # bound to every interface: the token guards it (a documented choice)
            return True
        if host is None:
            return False
        name = _host_name(host)
        return loopback_host(name) or name == self.host

    def _origin_ok(self, origin: str, host: str | None, scheme: str) -> bool:
        seen = origin_of(origin)
        if seen is None:
            return False  # "null" (a sandboxed frame, a file), or not an origin at all
        if seen in self.allow_origins:
            return True
        own = origin_of(f"{'https' if scheme in ('https', 'wss') else 'http'}://{host}")
        return own is not None and seen == own

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers: dict[bytes, str] = {}
        for key, value in scope.get("headers", []):
            headers.setdefault(bytes(key).lower(), bytes(value).decode("latin-1"))
        host = headers.get(b"host")
        websocket = scope["type"] == "websocket"
        method = "GET" if websocket else str(scope.get("method", "GET")).upper()
        refusal = self._refusal(scope, headers, host, method, websocket)
        if refusal is not None:
            status, answer = refusal
            if websocket:
                reason = str(answer["error"])[:120]
                await send({"type": "websocket.close", "code": 1008, "reason": reason})
            else:
                await _json(send, status, answer)
            return
        if websocket:
            await self.app(scope, receive, send)
            return

        async def secured(message: Message) -> None:
            if message["type"] == "http.response.start":
                message = {**message, "headers": [*message.get("headers", []), *SECURITY_HEADERS]}
            await send(message)

        changing = method in STATE_CHANGING
        routed, takes_none = self._kind(scope, method) if changing else (False, False)
        if routed:
            kind = headers.get(b"content-type", "").split(";")[0].strip().lower()
            if kind != "application/json":
                await _json(send, 415, _not_json(kind))
                return
            if takes_none:
                body = await _read_body(receive)
                if not _empty_object(body):
                    await _json(send, 422, EMPTY_BODY)
                    return
                receive = _replay(body, receive)
        await self.app(scope, receive, secured)

    def _refusal(
        self, scope: Scope, headers: dict[bytes, str], host: str | None, method: str, ws: bool
    ) -> tuple[int, dict[str, object]] | None:
        if not self.host_ok(host):
            extra = self.host and not loopback_host(self.host)
            allowed = "localhost, 127.0.0.1, [::1]" + (f", {self.host}" if extra else "")
            return 400, {
                "error": f"Host {host!r} is not this plant's (allowed: {allowed})",
                "field": "host",
                "allowed": allowed,
            }
        origin = headers.get(b"origin")
        scheme = str(scope.get("scheme", "http"))
        if origin is not None and (ws or method in STATE_CHANGING):
            if not self._origin_ok(origin, host, scheme):
                return 403, _foreign(f"Origin {origin!r}")
            return None
        site = headers.get(b"sec-fetch-site", "").lower()
        if site in ("cross-site", "same-site"):
            navigation = (
                headers.get(b"sec-fetch-mode", "").lower() == "navigate"
                and method == "GET"
                and scope.get("path") in NAVIGATION_PAGES
            )
            if not navigation and not (
                origin is not None and origin_of(origin) in self.allow_origins
            ):
                return 403, _foreign(f"a request from another site (Sec-Fetch-Site: {site})")
        return None


def _foreign(what: str) -> dict[str, object]:
    return {
        "error": f"{what} may not use this plant's API (allowed: the plant's own pages,"
        " and the origins given with --allow-origin)",
        "field": "origin",
    }


def _not_json(kind: str) -> dict[str, object]:
    return {
        "error": f"Content-Type {kind or 'missing'!r}: a request that changes the plant"
        " sends a JSON body (allowed: application/json; {} when the route takes no body)",
        "field": "content-type",
        "allowed": "application/json",
    }


EMPTY_BODY: dict[str, object] = {
    "error": "body: this route takes no value (allowed: {}, an empty JSON object)",
    "field": "body",
    "allowed": "{}",
}


def _empty_object(body: bytes) -> bool:
    try:
        value = json.loads(body)
    except (ValueError, RecursionError):
        return False
    return isinstance(value, dict) and not value


async def _read_body(receive: Receive) -> bytes:
    """The whole body (BodyLimit, outside, bounds it)."""
    chunks: list[bytes] = []
    while True:
        message = await receive()
        if message["type"] != "http.request":
            break
        chunks.append(message.get("body", b""))
        if not message.get("more_body", False):
            break
    return b"".join(chunks)


def _replay(body: bytes, then: Receive) -> Receive:
    """The body read once more, then what the connection says (a disconnect)."""
    sent = False

    async def receive() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        return await then()

    return receive


__all__ = ["MAX_BODY", "STATE_CHANGING", "BodyLimit", "BrowserGate", "TokenGate", "origin_of"]
