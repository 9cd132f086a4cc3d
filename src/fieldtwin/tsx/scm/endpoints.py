"""What a channel's connector is wired to: an in-memory peer, a pty, a serial device, TCP.

The in-memory peer lives in simulated time (its characters arrive at its own
format and speed, so a peer with another format yields parity and format
errors).  The real endpoints come from ``fieldtwin.transports`` and are pumped
by the PLC's pacer (fieldtwin.facade.host opens them), which then paces time.

A pty shows its master's line settings (issue 23, fieldtwin.transports.pty.PeerLine):
when its speed or odd parity differ from the channel's, the characters are received
as the module's UART would sample them, as from a memory peer at that format - the
parity and format faults of SCM 6.3.
"""

from __future__ import annotations

import contextlib
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Protocol

from fieldtwin.charformat import CharFormat, Parity
from fieldtwin.clock import SimClock
from fieldtwin.errors import TransportError
from fieldtwin.tsx.scm.line import Line

MAX_CONNECTION_NAMES = 16  # the last TCP peers a channel remembers (DESIGN rule 14)


class CharTap(Protocol):
    """Who publishes a channel's characters (fieldtwin.runtime.wiretap.CharTap)."""

    @property
    def active(self) -> bool: ...

    def chars(self, direction: str, data: bytes, now: int | None = None) -> None: ...


class MasterLine(Protocol):
    """What a pty shows of its master's settings (fieldtwin.transports.pty.PeerLine)."""

    def differs(self, own: CharFormat) -> bool: ...

    def seen_as(self, own: CharFormat) -> CharFormat | None: ...


class MemoryPeer:
    """The far end of a channel wired to ``"memory"``: send to the module, receive from it."""

    name = "memory"
    peer_path: str | None = None
    is_real = False

    def __init__(self, clock: SimClock, line: Line) -> None:
        self.closed = False
        self.format: CharFormat | None = None  # None: the channel's own format and speed
        self.baud: int | None = None  # None: the channel's present speed
        self.log: list[tuple[int, int]] = []  # (simulated time, byte) of what the module sent
        self._clock = clock
        self._line = line
        self._inbox = bytearray()
        self.tap: CharTap | None = None  # the plant's event bus, when the binder gave one

    def set_format(
        self, data_bits: int = 8, parity: str = "N", stop_bits: int = 1, baud: int | None = None
    ) -> None:
        """Make the peer's UART differ from the channel's (SCM 6.3 parity / format faults)."""
        fmt = Parity.parse(parity, "peer parity")
        self.format = CharFormat(baud or self._line.baud, data_bits, fmt, stop_bits)
        self.baud = baud

    def send(self, data: bytes) -> None:
        """Characters typed by the peer now (simulated time); they arrive at the peer's pace."""
        if self.closed:
            raise TransportError("cannot send on the memory peer: it is closed")
        if self.tap is not None and self.tap.active:
            self.tap.chars("in", bytes(data))
        self._line.feed(bytes(data), self._clock.now, self.format, peer_speed=self.baud is not None)

    def receive(self) -> bytes:
        data = bytes(self._inbox)
        self._inbox.clear()
        return data

    def fileno(self) -> int | None:
        return None

    def close(self) -> None:
        self.closed = True

    def from_module(self, data: bytes) -> None:
        now = self._clock.now
        self._inbox += data
        self.log.extend((now, b) for b in data)


@dataclass(slots=True)
class Port:
    """A channel's wiring."""

    url: str
    line: Line
    peer: Any = None  # MemoryPeer or a Transport
    listener: Any = None
    runner: Any = None
    path: str | None = None
    connections: deque[str] = field(default_factory=lambda: deque(maxlen=MAX_CONNECTION_NAMES))
    settings_given: bool = False  # the URL fixed baud/parity/data/stop: never follow
    follow_error: str | None = None
    tap: CharTap | None = None  # the plant's event bus, when the binder gave one
    master: MasterLine | None = None  # a pty: its master's settings, as last seen (issue 23)

    def follow(self, fmt: CharFormat) -> None:
        """Set a host serial port to the channel's configured format and speed (SCM 3.2).

        A port that refuses a setting keeps its previous one; ``follow_error`` says so
        in the status (some pty drivers refuse to change the character size of an open
        slave).  termios.error is not an OSError, hence the broad catch.
        """
        port = getattr(self.peer, "port", None)  # SerialTransport.port: the pyserial object
        if self.settings_given or port is None:
            return
        self.follow_error = None
        wanted = {"bytesize": fmt.data_bits, "parity": fmt.parity.letter, "stopbits": fmt.stop_bits}
        for key, value in {"baudrate": fmt.baud, **wanted}.items():
            old = getattr(port, key)
            if old == value:
                continue
            try:
                setattr(port, key, value)
            except Exception as exc:  # pyserial raises ValueError, termios.error
                setattr(port, f"_{key}", old)  # pyserial stored the value before it failed
                self.follow_error = f"host port refused {key}={value} ({exc})"

    def describe(self) -> str:
        if self.listener is not None:
            peer = self.peer.name if self.peer is not None and not self.peer.closed else "waiting"
            return f"{self.path} ({peer})"
        if self.path is not None:
            note = f" [{self.follow_error}]" if self.follow_error else ""
            return f"{self.url.split('?')[0]} {self.path}{note}"
        return self.url

    def send(self, data: bytes) -> None:
        if self.tap is not None and self.tap.active:
            self.tap.chars("out", data)
        peer = self.peer
        if isinstance(peer, MemoryPeer):
            peer.from_module(data)
            return
        if peer is None or peer.closed:
            return  # nobody on the line: the characters are lost
        with contextlib.suppress(TransportError):  # the peer went away: the line is open
            peer.send(data)

    def feed(self, data: bytes, now: int) -> None:
        if self.tap is not None and self.tap.active:
            self.tap.chars("in", data, now)
        self.line.feed(data, now, self._sender())

    def _sender(self) -> CharFormat | None:
        """The format a pty's master sends at, if it is not the channel's (None: the same)."""
        peer_line = getattr(self.peer, "peer_line", None)  # a pty's (transports/pty.py)
        if peer_line is None:
            return None
        news = peer_line()
        if news is not None:
            self.master = news
        own = self.line.fmt
        if self.master is None or not self.master.differs(own):
            return None
        return self.master.seen_as(own)  # None: a rate termios cannot name (the channel's)

    def close(self) -> None:
        for item in (self.peer, self.listener):
            if item is None:
                continue
            if self.runner is not None:
                self.runner.detach(item)
            item.close()
        self.peer = self.listener = None
