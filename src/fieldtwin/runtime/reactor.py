"""The runner's descriptors: links and listeners attached, read, drained, closed.

A ``Reactor`` holds what the runner pumps: transports (``attach``) whose bytes go to
``on_data(data, now)``, and listeners (``attach_listener``) whose connections go to
``on_connect(transport, now)``.  It never waits and never runs the clock: the pacing
(fieldtwin.runtime.pacing) waits on the wall and hands it what became ready
(``handle`` then ``deliver``), and ``pump`` runs between two instants.

* Transports with a descriptor are registered with the wall once (``watch``), so a
  connect or a close is O(1).  An ``FdTransport`` tells the reactor, its watcher,
  when output stays queued (``backlogged``: the descriptor is watched for writing
  until it drains) and when it closes (``closed``: its descriptor is forgotten
  before its number can be reused).  Other transports are checked for closing,
  memory transports are polled, and those that may queue output are flushed, on
  every ``pump``.
* Issue 10 item 3: while more than OUTPUT_BOUND answer bytes wait for a peer that
  does not read, the connection's requests are not read (a real device answers one
  request at a time); the kernel's buffers then hold the peer back, not our memory.
* Issue 10 item 1: after a failed accept (no descriptors, no buffers) the listener
  is left alone ACCEPT_BACKOFF_S, doubled on each failure up to ACCEPT_BACKOFF_MAX_S,
  then tried again; the condition is reported once, and its end too.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Collection
from contextlib import suppress
from dataclasses import dataclass
from typing import Protocol

from fieldtwin.clock import SimClock
from fieldtwin.errors import TransportError
from fieldtwin.runtime.wall import WallClock
from fieldtwin.transports.base import AcceptFailed, FdTransport, Flushable, Listener, Transport

DataCallback = Callable[[bytes, int], None]
CloseCallback = Callable[[int], None]
ConnectCallback = Callable[[Transport, int], None]
Report = Callable[[str], None]

MAX_WAIT_S = 0.25  # longest single wait: how fast a stop() from another thread is seen
POLL_WAIT_S = 0.005  # wait cap while output is queued or a real transport has no descriptor
OUTPUT_BOUND = 4096  # queued answer bytes past which a connection's requests wait
ACCEPT_BACKOFF_S = 0.01  # the first pause after a failed accept, doubled on each failure
ACCEPT_BACKOFF_MAX_S = 1.0


class AttachTap(Protocol):
    """Sees every attachment (a recording, fieldtwin.runtime.record): may wrap its callbacks."""

    def link(
        self, transport: Transport, on_data: DataCallback, on_close: CloseCallback | None
    ) -> tuple[DataCallback, CloseCallback | None]: ...

    def listener(self, listener: Listener, on_connect: ConnectCallback) -> ConnectCallback: ...


def to_stderr(message: str) -> None:
    print(f"fieldtwin: {message}", file=sys.stderr, flush=True)


@dataclass(slots=True)
class _Link:
    transport: Transport
    on_data: DataCallback
    on_close: CloseCallback | None
    fd: int | None
    hooked: bool  # an FdTransport that tells the reactor of its backlog and its close
    paused: bool = False  # reading stopped while its output is over OUTPUT_BOUND


@dataclass(slots=True)
class _Accepting:
    listener: Listener
    on_connect: ConnectCallback
    fd: int
    backoff: float = ACCEPT_BACKOFF_S
    retry_at: float | None = None  # wall time to watch the listener again
    failing: bool = False  # reported, not yet accepting again


class Reactor:
    """The transports and listeners of a runner, and what their descriptors tell."""

    def __init__(self, clock: SimClock, wall: WallClock, report: Report = to_stderr) -> None:
        self.clock = clock
        self.wall = wall
        self.report = report
        self.tap: AttachTap | None = None  # a recording: sees every attachment (set_tap)
        self.real = 0  # attached transports that are real (not memory)
        self._pace_holders = 0  # servers of real lines that keep the run paced
        self._links: dict[int, _Link] = {}  # id(transport) -> link
        self._listeners: dict[int, _Accepting] = {}  # id(listener) -> entry
        self._by_fd: dict[int, _Link | _Accepting] = {}
        self._polled: list[_Link] = []  # transports without a descriptor (memory)
        self._unhooked: list[_Link] = []  # descriptors of other transports: checked for closing
        self._flushers: list[Flushable] = []  # other transports that may queue output
        self._backlog: dict[int, _Link] = {}  # fd -> hooked link with queued output
        self._closed: list[_Link] = []  # hooked links that closed themselves
        self._retrying: dict[int, _Accepting] = {}

    # ----------------------------------------------------------------- what is attached

    @property
    def attached(self) -> bool:
        """Something is attached (a transport or a listener)."""
        return bool(self._links) or bool(self._listeners)

    @property
    def holds_pace(self) -> bool:
        """A real transport, a listener or a pace holder is there: time follows the wall."""
        return self.real > 0 or bool(self._listeners) or self._pace_holders > 0

    def hold_pace(self, on: bool) -> None:
        """A server of a real line (``on``) holds the pace while it is open (issue 15 item
        2: a serial peer that closes does not end the pacing); counted."""
        self._pace_holders = max(0, self._pace_holders + (1 if on else -1))

    @property
    def watched(self) -> int:
        """Descriptors watched (links and listeners)."""
        return len(self._by_fd)

    @property
    def polled(self) -> bool:
        """A transport without a descriptor is attached: it is read after every instant."""
        return bool(self._polled)

    # ----------------------------------------------------------------- attachments

    def attach(
        self, transport: Transport, on_data: DataCallback, on_close: CloseCallback | None = None
    ) -> None:
        if transport.closed:
            raise TransportError(f"cannot attach {transport.name}: it is closed")
        self.detach(transport)
        if self.tap is not None:
            on_data, on_close = self.tap.link(transport, on_data, on_close)
        hooked = isinstance(transport, FdTransport)
        link = _Link(transport, on_data, on_close, transport.fileno(), hooked)
        self._links[id(transport)] = link
        self.real += transport.is_real
        if link.fd is None:
            self._polled.append(link)
        else:
            self._by_fd[link.fd] = link
            self.wall.watch(link.fd)
            if not hooked:
                self._unhooked.append(link)
        if isinstance(transport, FdTransport):
            transport.watcher = self
            if transport.pending_output:
                self.backlogged(transport)
        elif isinstance(transport, Flushable):  # a Protocol check: once per attachment
            self._flushers.append(transport)

    def attach_listener(self, listener: Listener, on_connect: ConnectCallback) -> None:
        self.detach(listener)
        if self.tap is not None:
            on_connect = self.tap.listener(listener, on_connect)
        entry = _Accepting(listener, on_connect, listener.fileno())
        self._listeners[id(listener)] = entry
        self._by_fd[entry.fd] = entry
        self.wall.watch(entry.fd)

    def set_tap(self, tap: AttachTap) -> None:
        self.tap = tap
        for link in self._links.values():
            link.on_data, link.on_close = tap.link(link.transport, link.on_data, link.on_close)
        for entry in self._listeners.values():
            entry.on_connect = tap.listener(entry.listener, entry.on_connect)

    def detach(self, transport_or_listener: Transport | Listener) -> None:
        key = id(transport_or_listener)
        link = self._links.pop(key, None)
        if link is not None:
            self._unindex(link)
            return
        entry = self._listeners.pop(key, None)
        if entry is not None:
            self._retrying.pop(key, None)
            self._forget(entry.fd, entry)

    def _unindex(self, link: _Link) -> None:
        transport = link.transport
        self.real -= transport.is_real
        if isinstance(transport, FdTransport) and transport.watcher is self:
            transport.watcher = None
        if link.fd is None:
            self._polled.remove(link)
        else:
            self._forget(link.fd, link)
            if not link.hooked:
                self._unhooked.remove(link)
        if not link.hooked and isinstance(transport, Flushable) and transport in self._flushers:
            self._flushers.remove(transport)

    def _forget(self, fd: int, owner: _Link | _Accepting) -> None:
        if self._by_fd.get(fd) is owner:
            del self._by_fd[fd]
            self.wall.forget(fd)
        if self._backlog.get(fd) is owner:
            del self._backlog[fd]

    # -- what an FdTransport tells its watcher (fieldtwin.transports.base.TransportWatcher)

    def backlogged(self, transport: FdTransport) -> None:
        """Output stays queued: watch for writability; over the bound, stop reading."""
        link = self._links.get(id(transport))
        if link is None or link.fd is None:
            return
        self._backlog[link.fd] = link
        if transport.pending_output > OUTPUT_BOUND:
            link.paused = True
        self.wall.watch(link.fd, read=not link.paused, write=True)

    def closed(self, transport: FdTransport) -> None:
        """It is closing: forget its descriptor now (its number may be reused at once)."""
        link = self._links.get(id(transport))
        if link is None or link.fd is None:
            return
        self._forget(link.fd, link)
        self._closed.append(link)

    # ----------------------------------------------------------------- between waits

    def wait_cap(self) -> float:
        """The longest the next wait may be: shorter while a listener backs off, a real
        transport has no descriptor or output is queued for a transport that has none."""
        cap = MAX_WAIT_S
        if self._retrying:
            soonest = min(e.retry_at or 0.0 for e in self._retrying.values())
            cap = min(cap, max(0.0, soonest - self.wall.monotonic()))
        # each list looked at only when it holds something (sockets and ptys alone: none)
        if (self._polled and any(lk.transport.is_real for lk in self._polled)) or (
            self._flushers and self._output_queued()
        ):
            cap = min(cap, POLL_WAIT_S)
        return cap

    def _output_queued(self) -> bool:
        return any(transport.pending_output for transport in self._flushers)

    def pump(self) -> None:
        """Poll descriptor-less transports, flush queued output, notice closed transports.

        O(1) in the number of TCP connections: closes and backlogs are told by
        the transports themselves; only other kinds of transport are scanned.
        """
        if self._polled:
            for link in self._polled.copy():
                self._read(link)
        while self._closed:
            link = self._closed.pop()
            if self._links.get(id(link.transport)) is link:
                self._gone(link)
        for link in self._unhooked:
            if link.transport.closed:
                self._gone(link)
                return  # the list changed; the next cycle sees the rest
        for transport in self._flushers:
            if transport.pending_output:
                with suppress(TransportError):  # it closed itself: noticed on the next cycle
                    transport.flush()
        if self._retrying:
            self._retry_listeners()

    def handle(self, ready: tuple[Collection[int], Collection[int]]) -> Collection[int]:
        """Flush the writable descriptors; return the readable ones."""
        readable, writable = ready
        for fd in writable:
            link = self._backlog.get(fd)
            if link is not None:
                self._drain(link)
        return readable

    def _drain(self, link: _Link) -> None:
        transport = link.transport
        assert isinstance(transport, FdTransport) and link.fd is not None
        try:
            transport.flush()
        except TransportError:
            return  # it closed itself: the watcher was told
        pending = transport.pending_output
        if pending and not (link.paused and pending <= OUTPUT_BOUND):
            return
        link.paused = False
        if not pending:
            del self._backlog[link.fd]
        self.wall.watch(link.fd, read=True, write=bool(pending))

    def deliver(self, ready: Collection[int]) -> None:
        """Read the readable links (at the clock's now), accept on the readable listeners."""
        for fd in ready:
            entry = self._by_fd.get(fd)
            if isinstance(entry, _Link):
                if not entry.paused:
                    self._read(entry)
            elif entry is not None:
                self._accept(entry)

    # ----------------------------------------------------------------- listeners

    def _accept(self, entry: _Accepting) -> None:
        accepted = False
        try:
            while (transport := entry.listener.accept()) is not None:
                accepted = True
                entry.on_connect(transport, self.clock.now)
        except AcceptFailed as exc:
            self._back_off(entry, exc)
            return
        except TransportError:
            self.detach(entry.listener)  # closed under us
            return
        if accepted and entry.failing:
            entry.failing = False
            entry.backoff = ACCEPT_BACKOFF_S
            self.report(f"{entry.listener.name}: accepting connections again")

    def _back_off(self, entry: _Accepting, exc: AcceptFailed) -> None:
        """Issue 10 item 1: leave the listener alone a while; report the condition once."""
        if not entry.failing:
            entry.failing = True
            self.report(
                f"{exc}; the connections already open are still served,"
                f" new ones are retried (backoff up to {ACCEPT_BACKOFF_MAX_S:g} s)"
            )
        self.wall.forget(entry.fd)
        entry.retry_at = self.wall.monotonic() + entry.backoff
        entry.backoff = min(entry.backoff * 2, ACCEPT_BACKOFF_MAX_S)
        self._retrying[id(entry.listener)] = entry

    def _retry_listeners(self) -> None:
        now = self.wall.monotonic()
        for key, entry in list(self._retrying.items()):
            if entry.retry_at is not None and entry.retry_at <= now:
                del self._retrying[key]
                entry.retry_at = None
                self.wall.watch(entry.fd)

    # ----------------------------------------------------------------- links

    def _read(self, link: _Link) -> None:
        if self._links.get(id(link.transport)) is not link:
            return  # detached by an earlier callback of the same delivery
        try:
            data = link.transport.receive()
        except TransportError:
            self._gone(link)
            return
        if data:
            link.on_data(data, self.clock.now)

    def _gone(self, link: _Link) -> None:
        self.detach(link.transport)
        if link.on_close is not None:
            link.on_close(self.clock.now)


__all__ = [
    "ACCEPT_BACKOFF_MAX_S",
    "ACCEPT_BACKOFF_S",
    "MAX_WAIT_S",
    "OUTPUT_BOUND",
    "POLL_WAIT_S",
    "AttachTap",
    "CloseCallback",
    "ConnectCallback",
    "DataCallback",
    "Reactor",
    "Report",
]
