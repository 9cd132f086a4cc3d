"""The real-time runner: paces the simulated clock and pumps transports into the cores.

Three ways to run, chosen afresh on every cycle (attachments may change):

* **free** - no real descriptor attached: events run back to back, memory
  transports are polled after each instant; ``advance`` with nothing attached
  is exactly ``clock.advance``.
* **paced** - a real transport or listener is attached and ``speed`` is a
  number: simulated time follows the wall clock at ``speed`` (x1, x10, ...).
  The runner sleeps only inside the wall's ``wait`` (selectors.select), until
  the next clock deadline mapped to wall time or until bytes arrive.  Bytes that
  arrive at wall time w are given the simulated time they arrived at; events due
  before it run first.  When the clock lags the wall it catches up without
  sleeping; simulated time never goes back.
* **fast** - real descriptors attached and ``speed=None``: events run back to
  back with a zero-timeout poll of the descriptors between instants; when no
  event is due before the end, the runner blocks for data and simulated time
  follows the wall clock at x1 while it waits (so a limit of n simulated
  seconds is also at most n wall seconds of waiting).

``run_forever``'s ticks are not clock events: they never keep the clock busy.
With nothing scheduled and no end, the runner waits on the wall (time follows
at ``speed``, or x1) instead of spinning.  Every single wait is at most
MAX_WAIT_S, so a ``stop()`` from another thread is seen within that time.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from contextlib import suppress
from dataclasses import dataclass

from fieldtwin.clock import SimClock
from fieldtwin.errors import ConfigError, TransportError
from fieldtwin.runtime.wall import SystemWall, WallClock
from fieldtwin.transports.base import Flushable, Listener, Transport

DataCallback = Callable[[bytes, int], None]
CloseCallback = Callable[[int], None]
ConnectCallback = Callable[[Transport, int], None]

MAX_WAIT_S = 0.25  # longest single wait: how fast a stop() from another thread is seen
POLL_WAIT_S = 0.005  # wait cap while output is queued or a real transport has no descriptor


@dataclass(slots=True)
class _Link:
    transport: Transport
    on_data: DataCallback
    on_close: CloseCallback | None


@dataclass(slots=True)
class _Pace:
    """The wall <-> simulated time mapping of one run: (wall0, sim0) at ``speed``."""

    wall0: float
    sim0: int
    speed: float

    def sim_at(self, wall: float) -> int:
        return self.sim0 + round((wall - self.wall0) * self.speed * 1_000_000)

    def wall_at(self, sim: int) -> float:
        return self.wall0 + (sim - self.sim0) / (self.speed * 1_000_000)


class Runner:
    """Runs a SimClock against the wall clock, delivering transport bytes as they arrive."""

    def __init__(
        self, clock: SimClock, speed: float | None = 1.0, *, wall: WallClock | None = None
    ) -> None:
        if speed is not None and not speed > 0:
            raise ConfigError(f"runner speed={speed!r}: allowed a factor > 0, or None (fastest)")
        self.clock = clock
        self.speed = speed
        self._wall: WallClock = wall or SystemWall()
        self._links: dict[int, _Link] = {}  # id(transport) -> link
        self._listeners: dict[int, tuple[Listener, ConnectCallback]] = {}
        self._by_fd: dict[int, _Link | tuple[Listener, ConnectCallback]] = {}
        self._fds: tuple[int, ...] = ()
        self._polled: list[_Link] = []  # transports without a descriptor (memory)
        self._fd_links: list[_Link] = []
        self._flushers: list[Flushable] = []  # transports that may queue output
        self._has_real = False
        self._predicate: Callable[[], bool] | None = None
        self._stopping = False
        self._tick: tuple[CloseCallback | None, int] | None = None
        self._next_tick = 0

    # ----------------------------------------------------------------- attachments

    def attach(
        self, transport: Transport, on_data: DataCallback, on_close: CloseCallback | None = None
    ) -> None:
        """Deliver bytes arriving on ``transport`` as ``on_data(data, now)``."""
        if transport.closed:
            raise TransportError(f"cannot attach {transport.name}: it is closed")
        self._links[id(transport)] = _Link(transport, on_data, on_close)
        self._reindex()

    def attach_listener(self, listener: Listener, on_connect: ConnectCallback) -> None:
        """Call ``on_connect(transport, now)`` for every accepted connection."""
        self._listeners[id(listener)] = (listener, on_connect)
        self._reindex()

    def detach(self, transport_or_listener: Transport | Listener) -> None:
        """Stop pumping it (it stays open); unknown objects are ignored."""
        key = id(transport_or_listener)
        if self._links.pop(key, None) is not None or self._listeners.pop(key, None) is not None:
            self._reindex()

    def _reindex(self) -> None:
        self._by_fd = {}
        self._polled = []
        self._fd_links = []
        for link in self._links.values():
            fd = link.transport.fileno()
            if fd is None:
                self._polled.append(link)
            else:
                self._by_fd[fd] = link
                self._fd_links.append(link)
        for entry in self._listeners.values():
            self._by_fd[entry[0].fileno()] = entry
        self._fds = tuple(self._by_fd)  # a new object: the wall re-registers
        # isinstance on a Protocol is slow: decide once per attachment, not once per cycle
        self._flushers = [
            lk.transport for lk in self._links.values() if isinstance(lk.transport, Flushable)
        ]
        real = any(lk.transport.is_real for lk in self._links.values())
        self._has_real = real or bool(self._listeners)

    @property
    def paced(self) -> bool:
        """True while a real transport or a listener is attached and speed is a number."""
        return self.speed is not None and self._has_real

    # ----------------------------------------------------------------- public runs

    def advance(self, duration_us: int) -> None:
        """Advance simulated time by ``duration_us`` (paced or not, see module docstring)."""
        if duration_us < 0:
            raise ConfigError(f"cannot advance by a negative time ({duration_us} us)")
        if not self._links and not self._listeners:
            self.clock.advance(duration_us)  # nothing to pump: the plain clock
            return
        self._run(self.clock.now + duration_us, None)

    def run_until(self, predicate: Callable[[], bool], limit_us: int) -> bool:
        """Advance until ``predicate()`` (checked after each instant and delivery) or the limit."""
        if limit_us < 0:
            raise ConfigError(f"run_until limit must be >= 0 us, got {limit_us}")
        if predicate():
            return True
        self._run(self.clock.now + limit_us, predicate)
        return predicate()

    def run_forever(self, on_tick: CloseCallback | None = None, tick_us: int = 200_000) -> None:
        """Run until ``stop()`` or Ctrl-C; ``on_tick(now)`` about every ``tick_us`` simulated."""
        if tick_us <= 0:
            raise ConfigError(f"tick_us must be > 0, got {tick_us}")
        self._tick = (on_tick, tick_us)
        self._next_tick = self.clock.now + tick_us
        try:
            self._run(None, None)
        except KeyboardInterrupt:
            pass
        finally:
            self._tick = None

    def stop(self) -> None:
        """End the current run (advance, run_until or run_forever) after the running instant."""
        self._stopping = True

    # ----------------------------------------------------------------- the loop

    def _run(self, end: int | None, predicate: Callable[[], bool] | None) -> None:
        self._stopping = False
        self._predicate = predicate
        pace = _Pace(self._wall.monotonic(), self.clock.now, self.speed or 1.0)
        try:
            while not self._done() and self._cycle(end, pace):
                pass
        finally:
            self._predicate = None
            self._stopping = False

    def _done(self) -> bool:
        return self._stopping or (self._predicate is not None and self._predicate())

    def _cycle(self, end: int | None, pace: _Pace) -> bool:
        """One wait-and-run step; False once the end is reached."""
        self._pump()
        if self._done():
            return False
        clock = self.clock
        deadline = clock.next_deadline()
        busy = deadline is not None and (end is None or deadline <= end)
        if not busy and end is not None and clock.now >= end:
            return False
        target = deadline if busy else end
        if self.paced:
            self._paced_step(self._soonest(target), end, pace)
        elif self._fds:
            self._fast_step(target, end, busy)
        elif target is not None:
            self._settle(target)
        else:
            self._idle(end)
        self._maybe_tick()
        return True

    def _soonest(self, target: int | None) -> int | None:
        """The target, or the next tick if it comes first (so paced ticks are on time)."""
        if self._tick is None:
            return target
        return self._next_tick if target is None else min(target, self._next_tick)

    def _maybe_tick(self) -> None:
        now = self.clock.now
        if self._tick is None or now < self._next_tick:
            return
        on_tick, tick_us = self._tick
        self._next_tick += tick_us * ((now - self._next_tick) // tick_us + 1)
        if on_tick is not None:
            on_tick(now)

    def _idle(self, end: int | None) -> None:
        """Nothing scheduled, nothing real, no end (run_forever): wait on the wall, time follows."""
        speed = self.speed or 1.0
        wake = self._soonest(end)
        timeout = MAX_WAIT_S if wake is None else (wake - self.clock.now) / 1_000_000 / speed
        start = self._wall.monotonic()
        self._wall.wait(self._fds, min(timeout, MAX_WAIT_S))
        waited = (self._wall.monotonic() - start) * speed
        self._settle(self._clamp(self.clock.now + round(waited * 1_000_000), end))

    def _paced_step(self, target: int | None, end: int | None, pace: _Pace) -> None:
        wall = self._wall
        if target is None:
            timeout = MAX_WAIT_S
        else:
            timeout = min(max(0.0, pace.wall_at(target) - wall.monotonic()), MAX_WAIT_S)
        ready = wall.wait(self._fds, min(timeout, self._wait_cap()))
        reached = self._clamp(pace.sim_at(wall.monotonic()), end)
        if ready:
            if not self._settle(reached):
                self._deliver(ready)
        else:
            self._settle(reached if target is None else min(target, reached))

    def _fast_step(self, target: int | None, end: int | None, busy: bool) -> None:
        wall = self._wall
        if busy:
            ready = wall.wait(self._fds, 0)
            if ready:
                self._deliver(ready)  # arrived while the clock stood at now
            elif target is not None:
                self._settle(target)
            return
        # Idle: wait for a peer, letting simulated time follow the wall at x1.
        start = wall.monotonic()
        wake = self._soonest(target)
        timeout = MAX_WAIT_S if wake is None else (wake - self.clock.now) / 1_000_000
        ready = wall.wait(self._fds, min(timeout, MAX_WAIT_S, self._wait_cap()))
        waited = round((wall.monotonic() - start) * 1_000_000)
        reached = self._clamp(self.clock.now + waited, end)
        if not self._settle(reached) and ready:
            self._deliver(ready)

    def _clamp(self, sim: int, end: int | None) -> int:
        """Never before now (time never goes back), never past the end."""
        sim = max(sim, self.clock.now)
        return sim if end is None else min(sim, end)

    def _wait_cap(self) -> float:
        if any(lk.transport.is_real for lk in self._polled) or self._output_queued():
            return POLL_WAIT_S
        return MAX_WAIT_S

    def _output_queued(self) -> bool:
        return any(transport.pending_output for transport in self._flushers)

    def _settle(self, until: int) -> bool:
        """Run events up to ``until`` one instant at a time; True if the run is done early."""
        clock = self.clock
        if not self._polled and self._predicate is None:
            clock.run_until(until)
            return self._stopping
        while (deadline := clock.next_deadline()) is not None and deadline <= until:
            clock.run_until(deadline)
            self._pump()
            if self._done():
                return True
        clock.run_until(until)
        return False

    # ----------------------------------------------------------------- pumping

    def _pump(self) -> None:
        """Poll descriptor-less transports, flush queued output, notice closed transports."""
        for link in self._polled.copy():
            self._read(link)
        for link in self._fd_links:
            if link.transport.closed:
                self._gone(link)
                return  # the lists were rebuilt; the next cycle sees the rest
        for transport in self._flushers:
            if transport.pending_output:
                with suppress(TransportError):  # it closed itself: noticed on the next cycle
                    transport.flush()

    def _deliver(self, ready: Collection[int]) -> None:
        for fd in ready:
            entry = self._by_fd.get(fd)
            if isinstance(entry, _Link):
                self._read(entry)
            elif entry is not None:
                self._accept(*entry)

    def _accept(self, listener: Listener, on_connect: ConnectCallback) -> None:
        while (transport := listener.accept()) is not None:
            on_connect(transport, self.clock.now)

    def _read(self, link: _Link) -> None:
        if id(link.transport) not in self._links:
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
