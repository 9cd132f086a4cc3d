"""An in-memory pair: the test default (python-can's virtual bus).

What one end sends, the other receives on its next ``receive``.  No file
descriptor, not real: a runner with only memory transports never waits for
the wall clock.  Closing one end is seen by the other like a TCP peer closing:
it drains what was already sent, then ``receive`` raises TransportError.
"""

from __future__ import annotations

from collections.abc import Callable

from fieldtwin.errors import TransportError


class MemoryTransport:
    """One end of a memory pair."""

    is_real = False
    peer_path: str | None = None

    def __init__(self, name: str) -> None:
        self.name = name
        self.closed = False
        self._inbox = bytearray()
        self._peer: MemoryTransport | None = None
        self._sends: Callable[[bytes], None] | None = None  # sees every send

    def __repr__(self) -> str:
        return f"<MemoryTransport {self.name} {'closed' if self.closed else 'open'}>"

    @property
    def pending_output(self) -> int:
        return 0

    def flush(self) -> None:
        """Nothing is ever queued: a memory send lands in the peer's inbox at once."""

    def observe_sends(self, observer: Callable[[bytes], None] | None) -> None:
        """``observer(data)`` sees every send from now on (None: none any more)."""
        self._sends = observer

    def send(self, data: bytes) -> None:
        if self.closed:
            raise TransportError(f"cannot send on {self.name}: it is closed")
        if self._sends is not None:
            self._sends(data)
        peer = self._peer
        if peer is None or peer.closed:
            raise TransportError(f"cannot send on {self.name}: the peer has closed")
        peer._inbox += data

    def receive(self) -> bytes:
        if self.closed:
            raise TransportError(f"cannot receive on {self.name}: it is closed")
        if self._inbox:
            data = bytes(self._inbox)
            self._inbox.clear()
            return data
        peer = self._peer
        if peer is not None and peer.closed:
            self.closed = True
            raise TransportError(f"{self.name}: the peer has closed")
        return b""

    def fileno(self) -> int | None:
        return None

    def close(self) -> None:
        self.closed = True
        self._inbox.clear()


def memory_pair(name: str = "memory") -> tuple[MemoryTransport, MemoryTransport]:
    """Two connected ends; both are named ``name``."""
    a = MemoryTransport(name)
    b = MemoryTransport(name)
    a._peer = b
    b._peer = a
    return a, b
