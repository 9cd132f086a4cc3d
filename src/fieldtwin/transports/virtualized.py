"""Which endpoints open now: real ones, or a replay's virtual twins (transports.virtual).

``open_pty``, ``open_serial`` and ``listen`` ask :func:`current`; a
``transports.virtual.Wiring`` in force (``with wiring:``) answers with its twins.
This module sits below both, so that the openers and the virtual twins (which
subclass the real transports) do not import each other.
"""

from __future__ import annotations

from contextvars import ContextVar
from typing import Protocol

from fieldtwin.transports.base import FdTransport, LineSettings, Listener


class VirtualEndpoints(Protocol):
    """What a replay's wiring opens instead of real endpoints."""

    def listener(self, host: str, port: int, max_connections: int) -> Listener: ...

    def pty(self, settings: LineSettings | None) -> FdTransport: ...

    def serial(self, device: str, settings: LineSettings | None) -> FdTransport: ...


CURRENT: ContextVar[VirtualEndpoints | None] = ContextVar("fieldtwin_virtual_wiring", default=None)


def current() -> VirtualEndpoints | None:
    """The wiring in force (None: open real endpoints)."""
    return CURRENT.get()


__all__ = ["CURRENT", "VirtualEndpoints", "current"]
