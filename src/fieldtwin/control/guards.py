"""The control API's two gates, as ASGI middleware: the body size bound and the token.

* ``BodyLimit``: a request body over ``max_bytes`` (64 KiB) gets 413 as soon as
  its Content-Length says so, or as soon as the bytes received pass the bound
  (chunked bodies): it is never read whole (DESIGN rule 14).
* ``TokenGate``: when the API is reachable from other machines a token is
  required on every request and WebSocket (``Authorization: Bearer TOKEN``, or
  ``?token=TOKEN`` where a header cannot be set); 401 without it.
"""

from __future__ import annotations

import json
import secrets
from urllib.parse import parse_qs

from starlette.types import ASGIApp, Message, Receive, Scope, Send

MAX_BODY = 64 * 1024


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

    def _given(self, scope: Scope) -> str | None:
        for key, value in scope.get("headers", []):
            if key == b"authorization":
                text = bytes(value).decode("latin-1")
                if text.lower().startswith("bearer "):
                    return text[7:].strip()
        raw: bytes = scope.get("query_string", b"")
        tokens = parse_qs(raw.decode("latin-1")).get("token", [])
        return tokens[0] if tokens else None

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if self.token is None or scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        given = self._given(scope)
        if given is not None and secrets.compare_digest(given.encode(), self.token.encode()):
            await self.app(scope, receive, send)
            return
        if scope["type"] == "websocket":
            await send({"type": "websocket.close", "code": 1008, "reason": "token required"})
            return
        await _json(
            send,
            401,
            {"error": "a token is required (Authorization: Bearer TOKEN)", "field": "token"},
        )


__all__ = ["MAX_BODY", "BodyLimit", "TokenGate"]
