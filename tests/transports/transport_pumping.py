"""Bounded helpers shared by the transport tests: every wait has a deadline."""

from __future__ import annotations

import select
import time

from fieldtwin.transports.base import Flushable, Transport

DEADLINE_S = 5.0


def _wait_readable(transport: Transport, timeout: float) -> None:
    fd = transport.fileno()
    if fd is not None:
        select.select([fd], [], [], timeout)


def flush(*transports: Transport) -> None:
    for transport in transports:
        if isinstance(transport, Flushable) and not transport.closed:
            transport.flush()


def collect(rx: Transport, tx: Transport, size: int, deadline_s: float = DEADLINE_S) -> bytes:
    """Receive on ``rx`` until ``size`` bytes arrived, flushing ``tx``; fail past the deadline."""
    buf = bytearray()
    end = time.monotonic() + deadline_s
    while len(buf) < size:
        assert time.monotonic() < end, f"only {len(buf)} of {size} bytes within {deadline_s} s"
        flush(tx)
        chunk = rx.receive()
        if chunk:
            buf += chunk
        else:
            _wait_readable(rx, 0.01)
    return bytes(buf)


def until(condition: object, deadline_s: float = DEADLINE_S) -> None:
    """Poll ``condition()`` (a callable) until true; fail past the deadline."""
    assert callable(condition)
    end = time.monotonic() + deadline_s
    while not condition():
        assert time.monotonic() < end, f"condition not met within {deadline_s} s"
        select.select([], [], [], 0.005)
