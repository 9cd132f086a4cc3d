"""The real-time runner: paces the simulated clock and pumps transports into the cores.

Three ways to run, chosen afresh on every cycle (attachments may change):

* **free** - no real descriptor attached: events run back to back, memory
  transports are polled after each instant; ``advance`` with nothing attached
  is exactly ``clock.advance``.
* **paced** - a real transport or listener is attached (or a server of a real
  line holds the pace, ``hold_pace``) and ``speed`` is a number: simulated time
  follows the wall clock at ``speed`` (x1, x10, ...).
  The runner sleeps only inside the wall's ``wait`` (selectors.select), until
  the next clock deadline mapped to wall time or until bytes arrive.  Bytes that
  arrive at wall time w are given the simulated time they arrived at; events due
  before it run first.  When the clock lags the wall it catches up without
  sleeping; simulated time never goes back.
* **fast** - real descriptors attached and ``speed=None``: events run back to
  back with a zero-timeout poll of the descriptors between instants; when no
  event is due before the end, the runner blocks for data and simulated time
  follows the wall clock at x1 while it waits (so a limit of n simulated
  seconds is also at most n wall seconds of waiting).  A wall may ask for
  fewer polls while events run (its ``fast_poll_s``; the system wall's is
  FAST_POLL_S): the descriptors are then polled between two instants only
  once that much wall time has passed since the last poll, and bytes that
  arrived meanwhile are given the instant of the poll that finds them, as
  always (at most ``fast_poll_s`` of wall time after they arrived).  Every
  run (``advance``, ``run_until``, ...) polls before its first instant, and
  after a poll that found bytes the next instant polls again: while a peer
  is sending, the polls are between every two instants, as without it.  Between
  two polls the instants run in one go (``_between_polls``): commands, ticks
  and the end are taken up at the next poll, a tick or the end stops the run
  of instants where a cycle per instant would have, and a ``run_until``
  predicate is still checked after every instant.  Other walls (the tests')
  have none: a poll between every two instants.

``run_forever``'s ticks are not clock events: they never keep the clock busy.
With nothing scheduled and no end, the runner waits on the wall (time follows
at ``speed``, or x1) instead of spinning.  Every single wait is at most
MAX_WAIT_S, so a ``stop()`` from another thread is seen within that time.
``stop()`` is a latch: a stop asked before a run starts ends it at once, nested
runs see it too, and only the outermost run it ends takes it down.

Catch-up is bounded (fieldtwin.runtime.pace, issue 20): a paced cycle that finds
the clock behind the wall runs at most CATCH_UP_SLICE_S of wall time of instants,
then serves commands, descriptors and the stop flag; once the clock lags its pace
by more than MAX_LAG_S the pace is moved to where the clock stands (the plant
runs as fast as it can, ``speed_reached`` says how fast; reported once).

Commands from other threads (the control API) come through an inbox
(fieldtwin.runtime.inbox) given to ``take_commands``: its wakeup descriptor is
watched with the transports, and its commands run on this thread between two
instants (at the start of a cycle), one at a time.  A command may itself run
the clock (``advance``, a power break, an exchange): such a nested run keeps
pumping the transports, takes no other command until it ends, and passes a
``stop()`` on to the run around it.  ``pause``/``resume`` hold simulated time
(the transports are not read while paused; the inbox still is), ``step`` and
``run_to`` run it by a given amount while paused or not, ``set_speed`` changes
the pace without a jump in simulated time.  ``start_mode`` is their form that
holds nothing: the outermost run goes on to the mode's end (paused or not)
between its cycles, taking commands all along; the end is a clock event (the
same in a replay), and a new mode or ``pause`` replaces the one in progress.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Collection
from contextlib import suppress
from dataclasses import dataclass
from typing import Protocol

from fieldtwin.clock import SimClock
from fieldtwin.errors import ConfigError, TransportError
from fieldtwin.runtime.inbox import Inbox
from fieldtwin.runtime.pace import (
    CATCH_UP_SLICE_S,
    MAX_LAG_S,
    REACHED_WINDOW_S,
    Mode,
    Pace,
    SpeedMeter,
    check_speed,
)
from fieldtwin.runtime.wall import SystemWall, WallClock
from fieldtwin.transports.base import AcceptFailed, FdTransport, Flushable, Listener, Transport

DataCallback = Callable[[bytes, int], None]
CloseCallback = Callable[[int], None]
ConnectCallback = Callable[[Transport, int], None]
Report = Callable[[str], None]

MAX_WAIT_S = 0.25  # longest single wait: how fast a stop() from another thread is seen
POLL_WAIT_S = 0.005  # wait cap while output is queued or a real transport has no descriptor
# Issue 10 item 3: while more than this many answer bytes wait for a peer that does not
# read, the runner stops reading that connection's requests (a real device answers one
# request at a time); the kernel's buffers then hold the peer back, not our memory.
OUTPUT_BOUND = 4096
# Issue 10 item 1: after a failed accept (no descriptors, no buffers) the listener is
# left alone this long, doubled on each failure up to the max, then tried again.
ACCEPT_BACKOFF_S = 0.01
ACCEPT_BACKOFF_MAX_S = 1.0
MODE_LAST = 1 << 30  # a mode's end runs after every other event of its instant


class AttachTap(Protocol):
    """Sees every attachment (a recording, fieldtwin.runtime.record): may wrap its callbacks."""

    def link(
        self, transport: Transport, on_data: DataCallback, on_close: CloseCallback | None
    ) -> tuple[DataCallback, CloseCallback | None]: ...

    def listener(self, listener: Listener, on_connect: ConnectCallback) -> ConnectCallback: ...


def _to_stderr(message: str) -> None:
    print(f"fieldtwin: {message}", file=sys.stderr, flush=True)


@dataclass(slots=True)
class _Link:
    transport: Transport
    on_data: DataCallback
    on_close: CloseCallback | None
    fd: int | None
    hooked: bool  # an FdTransport that tells the runner of its backlog and its close
    paused: bool = False  # reading stopped while its output is over OUTPUT_BOUND


@dataclass(slots=True)
class _Accepting:
    listener: Listener
    on_connect: ConnectCallback
    fd: int
    backoff: float = ACCEPT_BACKOFF_S
    retry_at: float | None = None  # wall time to watch the listener again
    failing: bool = False  # reported, not yet accepting again


class Runner:
    """Runs a SimClock against the wall clock, delivering transport bytes as they arrive."""

    def __init__(
        self,
        clock: SimClock,
        speed: float | None = 1.0,
        *,
        wall: WallClock | None = None,
        report: Report | None = None,
    ) -> None:
        self.clock = clock
        self.speed = check_speed(speed, "runner speed")
        self.report: Report = report or _to_stderr
        self._wall: WallClock = wall or SystemWall()
        # fast mode: the least wall time between two polls while events run (0: every instant)
        self._fast_poll: float = getattr(self._wall, "fast_poll_s", 0.0)
        self._next_poll = float("-inf")  # wall time of the next such poll
        self._links: dict[int, _Link] = {}  # id(transport) -> link
        self._listeners: dict[int, _Accepting] = {}  # id(listener) -> entry
        self._by_fd: dict[int, _Link | _Accepting] = {}
        self._polled: list[_Link] = []  # transports without a descriptor (memory)
        self._unhooked: list[_Link] = []  # descriptors of other transports: checked for closing
        self._flushers: list[Flushable] = []  # other transports that may queue output
        self._backlog: dict[int, _Link] = {}  # fd -> hooked link with queued output
        self._closed: list[_Link] = []  # hooked links that closed themselves
        self._retrying: dict[int, _Accepting] = {}
        self._real = 0
        self._predicate: Callable[[], bool] | None = None
        self._stopping = False
        self._tick: tuple[CloseCallback | None, int] | None = None
        self._next_tick = 0
        self._inbox: Inbox | None = None
        self._in_command = False  # a command is running: the inbox waits for it
        self._paused = False
        self._stepping = 0  # nested runs of step/run_to: they run while paused
        self._depth = 0  # nested _run calls (a command that runs the clock)
        self._paces: list[Pace] = []  # the pace of every run in progress, outermost first
        self.tap: AttachTap | None = None  # a recording: sees every attachment (set_tap)
        self._pace_holders = 0  # servers of real lines that keep the run paced (hold_pace)
        self._mode: Mode | None = None  # a step, run-until, power break in progress
        self._meter = SpeedMeter()
        self._lagged_at = float("-inf")  # wall time the pace was last moved (speed not kept)
        self._lag_told = False

    # ----------------------------------------------------------------- attachments

    def attach(
        self, transport: Transport, on_data: DataCallback, on_close: CloseCallback | None = None
    ) -> None:
        """Deliver bytes arriving on ``transport`` as ``on_data(data, now)``."""
        if transport.closed:
            raise TransportError(f"cannot attach {transport.name}: it is closed")
        self.detach(transport)
        if self.tap is not None:
            on_data, on_close = self.tap.link(transport, on_data, on_close)
        hooked = isinstance(transport, FdTransport)
        link = _Link(transport, on_data, on_close, transport.fileno(), hooked)
        self._links[id(transport)] = link
        self._real += transport.is_real
        if link.fd is None:
            self._polled.append(link)
        else:
            self._by_fd[link.fd] = link
            self._wall.watch(link.fd)
            if not hooked:
                self._unhooked.append(link)
        if isinstance(transport, FdTransport):
            transport.watcher = self
            if transport.pending_output:
                self.backlogged(transport)
        elif isinstance(transport, Flushable):  # a Protocol check: once per attachment
            self._flushers.append(transport)

    def attach_listener(self, listener: Listener, on_connect: ConnectCallback) -> None:
        """Call ``on_connect(transport, now)`` for every accepted connection."""
        self.detach(listener)
        if self.tap is not None:
            on_connect = self.tap.listener(listener, on_connect)
        entry = _Accepting(listener, on_connect, listener.fileno())
        self._listeners[id(listener)] = entry
        self._by_fd[entry.fd] = entry
        self._wall.watch(entry.fd)

    def set_tap(self, tap: AttachTap) -> None:
        """From now on ``tap`` sees every attachment; those already made first, in order."""
        self.tap = tap
        for link in self._links.values():
            link.on_data, link.on_close = tap.link(link.transport, link.on_data, link.on_close)
        for entry in self._listeners.values():
            entry.on_connect = tap.listener(entry.listener, entry.on_connect)

    def detach(self, transport_or_listener: Transport | Listener) -> None:
        """Stop pumping it (it stays open); unknown objects are ignored.  O(1) for a
        descriptor, O(descriptor-less transports) for the others."""
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
        self._real -= transport.is_real
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
            self._wall.forget(fd)
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
        self._wall.watch(link.fd, read=not link.paused, write=True)

    def closed(self, transport: FdTransport) -> None:
        """It is closing: forget its descriptor now (its number may be reused at once)."""
        link = self._links.get(id(transport))
        if link is None or link.fd is None:
            return
        self._forget(link.fd, link)
        self._closed.append(link)

    # -- precise waits (issue 15 item 2: wire-timed RTU replies; docs/modbus.md)

    def want_precise_waits(self, on: bool) -> None:
        """A core whose deadlines must be met to a fraction of a millisecond on the wall
        (``on``), or that no longer needs it; a wall without the ability ignores it."""
        want = getattr(self._wall, "want_precision", None)
        if want is not None:
            want(on)

    # -- pace holders (issue 15 item 2: a serial peer that closes does not end the pacing)

    def hold_pace(self, on: bool) -> None:
        """A server of a real line (``on``) keeps the run paced at ``speed`` while it is
        open, even once its transport has gone (a serial peer that closed)."""
        self._pace_holders = max(0, self._pace_holders + (1 if on else -1))

    @property
    def paced(self) -> bool:
        """True while a real transport, a listener or a pace holder is there and speed
        is a number."""
        if self.speed is None:
            return False
        return self._real > 0 or bool(self._listeners) or self._pace_holders > 0

    @property
    def watched(self) -> int:
        """Descriptors the runner is watching (links and listeners)."""
        return len(self._by_fd)

    # ----------------------------------------------------------------- commands, clock

    def take_commands(self, inbox: Inbox | None) -> None:
        """Run the commands of ``inbox`` between instants (None: take no more)."""
        if self._inbox is not None:
            self._wall.forget(self._inbox.fileno())
        self._inbox = inbox
        if inbox is not None:
            self._wall.watch(inbox.fileno())

    def _commands(self) -> None:
        inbox = self._inbox
        if inbox is None or self._in_command:
            return
        self._in_command = True
        try:
            inbox.run_pending()
        finally:
            self._in_command = False

    @property
    def paused(self) -> bool:
        return self._paused

    def pause(self) -> None:
        """Hold simulated time (from the simulation's thread: a command); a mode in
        progress ends here (cut)."""
        self.end_mode()
        self._paused = True
        self._meter.reset()

    def resume(self) -> None:
        """Let simulated time run again, from where it stood (no jump)."""
        if self._paused:
            self._paused = False
            self._repace()
            self._meter.reset()

    def set_speed(self, speed: float | None) -> None:
        """A new speed factor (None: as fast as possible), effective at once, no jump."""
        self.speed = check_speed(speed, "runner speed")
        self._repace()
        self._meter.reset()
        self._lagged_at = float("-inf")

    # -- modes (issue 20 item 5): long runs that hold nothing

    @property
    def mode(self) -> Mode | None:
        """The mode in progress (its ``name`` and ``until``), or None."""
        return self._mode

    def start_mode(
        self, name: str, until_us: int, on_end: Callable[[int, bool], None] | None = None
    ) -> Mode:
        """Run simulated time to ``until_us`` (paused or not) between the runner's cycles;
        ``on_end(now, cut)`` at its end, a clock event after the others of its instant.
        The mode in progress, if any, ends first (cut)."""
        if until_us < self.clock.now:
            raise ConfigError(
                f"cannot run until t = {until_us / 1e6:g} s: simulated time is already"
                f" {self.clock.now / 1e6:.6f} s and never goes back"
            )
        self.end_mode()
        mode = Mode(name, until_us, on_end)
        mode.handle = self.clock.schedule(until_us, lambda now: self._mode_due(mode), MODE_LAST)
        self._mode = mode
        self._repace()  # from where the clock stands, paused or not
        self._meter.reset()
        return mode

    def end_mode(self) -> None:
        """End the mode in progress now (cut); nothing if none."""
        mode = self._mode
        if mode is None:
            return
        self._mode = None
        if mode.handle is not None:
            mode.handle.cancel()
        if mode.on_end is not None:
            mode.on_end(self.clock.now, True)

    def _mode_due(self, mode: Mode) -> None:
        if self._mode is mode:
            self._mode = None
            if self._paused:
                self._meter.reset()
            if mode.on_end is not None:
                mode.on_end(self.clock.now, False)

    # -- the speed reached (issue 20 item 1)

    @property
    def speed_reached(self) -> float | None:
        """Simulated seconds per wall second over the last REACHED_WINDOW_S while time
        runs (None while held or before two samples)."""
        return None if self._holding() else self._meter.reached

    @property
    def lagging(self) -> bool:
        """True while the plant does not keep ``speed`` (the pace was moved lately)."""
        return self._wall.monotonic() - self._lagged_at < REACHED_WINDOW_S

    def _keep_pace(self, woke: float, pace: Pace) -> None:
        """After a paced cycle: sample the speed; move the pace if the clock lags too far."""
        self._meter.sample(woke, self.clock.now)
        if woke - pace.wall_at(self.clock.now) <= MAX_LAG_S:
            return
        self._repace()
        self._lagged_at = woke
        self._next_tick = min(self._next_tick, self.clock.now)  # ticks come on the wall too
        if not self._lag_told:
            self._lag_told = True
            self.report(
                f"the plant cannot keep speed x{pace.speed:g}: it runs as fast as it can"
                " (the speed reached is in GET /clock and the status line)"
            )

    def step(self, duration_us: int) -> None:
        """Run simulated time by ``duration_us`` at the current speed, paused or not."""
        if duration_us < 0:
            raise ConfigError(f"cannot step by a negative time ({duration_us} us)")
        self._stepping += 1
        try:
            self._run(self.clock.now + duration_us, None)
        finally:
            self._stepping -= 1

    def run_to(self, t_us: int) -> None:
        """Run simulated time until ``t_us`` (never back), paused or not."""
        if t_us < self.clock.now:
            raise ConfigError(
                f"cannot run until t = {t_us / 1e6:g} s: simulated time is already"
                f" {self.clock.now / 1e6:.6f} s and never goes back"
            )
        self.step(t_us - self.clock.now)

    def _repace(self) -> None:
        wall, now = self._wall.monotonic(), self.clock.now
        for pace in self._paces:
            pace.wall0, pace.sim0, pace.speed = wall, now, self.speed or 1.0

    def _holding(self) -> bool:
        """Paused, with an inbox to resume from, outside a step and a command's own run."""
        return (
            self._paused
            and self._inbox is not None
            and not self._stepping
            and self._depth == 1
            and self._mode is None
        )

    def _hold(self) -> None:
        """Paused: no simulated time, no transport read; wait for a command (bounded)."""
        assert self._inbox is not None
        self._inbox.wait(MAX_WAIT_S)
        self._commands()
        if not self._paused:
            self._repace()

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
        """End the current run (advance, run_until or run_forever) after the running
        instant; asked before a run starts, it ends that run at once (a latch)."""
        self._stopping = True

    @property
    def running(self) -> bool:
        """A run (advance, run_until, run_forever) is in progress."""
        return self._depth > 0

    @property
    def stopping(self) -> bool:
        """A stop is asked and not yet taken by the run it ends."""
        return self._stopping

    # ----------------------------------------------------------------- the loop

    def _run(self, end: int | None, predicate: Callable[[], bool] | None) -> None:
        outer = self._predicate
        self._predicate = predicate
        pace = Pace(self._wall.monotonic(), self.clock.now, self.speed or 1.0)
        self._next_poll = float("-inf")  # a run polls before its first instant
        self._paces.append(pace)
        self._depth += 1
        try:
            while not self._done() and self._cycle(end, pace):
                pass
        finally:
            self._depth -= 1
            self._paces.pop()
            self._predicate = outer
            # the stop latch: a nested run (a command's advance) passes it on to the run
            # around it; the outermost run takes it down
            if self._depth == 0:
                self._stopping = False

    def _done(self) -> bool:
        return self._stopping or (self._predicate is not None and self._predicate())

    def _cycle(self, end: int | None, pace: Pace) -> bool:
        """One wait-and-run step; False once the end is reached."""
        self._commands()
        if self._holding():
            self._hold()
            return True
        self._pump()
        if self._done():
            return False
        clock = self.clock
        deadline = clock.next_deadline()
        busy = deadline is not None and (end is None or deadline <= end)
        if not busy and end is not None and clock.now >= end:
            return False
        mode = self._mode
        if mode is not None and self._depth == 1:  # never past a mode's end in one go
            end = mode.until if end is None else min(end, mode.until)
            busy = deadline is not None and deadline <= end
        target = deadline if busy else end
        if self.paced:
            self._paced_step(self._soonest(target), end, pace)
        elif self._by_fd:
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
        self._handle(self._wall.wait(min(timeout, self._wait_cap())))
        woke = self._wall.monotonic()
        self._settle(self._clamp(self.clock.now + round((woke - start) * speed * 1e6), end))
        self._meter.sample(woke, self.clock.now)

    def _paced_step(self, target: int | None, end: int | None, pace: Pace) -> None:
        wall = self._wall
        # a wall's lead (precise waits: wire-timed replies) runs a due instant that much
        # wall time early; bytes that arrive are still timed by the wall as it is
        lead: float = getattr(wall, "lead_s", 0.0)
        if target is None:
            timeout = MAX_WAIT_S
        else:
            timeout = min(max(0.0, pace.wall_at(target) - lead - wall.monotonic()), MAX_WAIT_S)
        ready = self._handle(wall.wait(min(timeout, self._wait_cap())))
        woke = wall.monotonic()
        reached = self._clamp(pace.sim_at(woke), end)
        if ready:  # catch up (a slice at most), then the bytes at the time reached
            if not self._settle(reached, woke + CATCH_UP_SLICE_S):
                self._deliver(ready)
        elif target is None:
            self._settle(reached)
        else:
            if lead and woke + lead >= pace.wall_at(target):
                reached = max(reached, self._clamp(target, end))
            self._settle(min(target, reached))  # one instant at most
        self._keep_pace(woke, pace)

    def _fast_step(self, target: int | None, end: int | None, busy: bool) -> None:
        wall = self._wall
        if busy:
            if self._fast_poll:
                now_wall = wall.monotonic()
                if now_wall < self._next_poll:  # polled less than fast_poll_s ago
                    self._between_polls(target, end)
                    return
                self._next_poll = now_wall + self._fast_poll
            ready = self._handle(wall.wait(0))
            self._meter.sample(wall.monotonic(), self.clock.now)
            if ready:
                self._next_poll = float("-inf")  # while bytes keep coming: every instant
                self._deliver(ready)  # arrived while the clock stood at now
            elif target is not None:
                self._settle(target)
            return
        # Idle: wait for a peer, letting simulated time follow the wall at x1.
        start = wall.monotonic()
        wake = self._soonest(target)
        timeout = MAX_WAIT_S if wake is None else (wake - self.clock.now) / 1_000_000
        ready = self._handle(wall.wait(min(timeout, MAX_WAIT_S, self._wait_cap())))
        woke = wall.monotonic()
        reached = self._clamp(self.clock.now + round((woke - start) * 1_000_000), end)
        if not self._settle(reached) and ready:
            self._deliver(ready)
        self._meter.sample(woke, self.clock.now)

    def _between_polls(self, target: int | None, end: int | None) -> None:
        """Fast mode, no poll due: run instants back to back (each settled as a cycle
        would) until ``fast_poll_s`` of wall time has passed since the last poll, the
        end, the next tick or a stop; the cycle around then polls, ticks, takes commands."""
        clock, wall = self.clock, self._wall
        limit = end
        if self._tick is not None:
            limit = self._next_tick if limit is None else min(limit, self._next_tick)
        next_poll = self._next_poll
        while target is not None:
            if self._settle(target):
                return
            target = clock.next_deadline()
            if target is None or (limit is not None and target > limit):
                return
            if wall.monotonic() >= next_poll:
                return

    def _clamp(self, sim: int, end: int | None) -> int:
        """Never before now (time never goes back), never past the end."""
        sim = max(sim, self.clock.now)
        return sim if end is None else min(sim, end)

    def _wait_cap(self) -> float:
        cap = MAX_WAIT_S
        if self._retrying:
            soonest = min(e.retry_at or 0.0 for e in self._retrying.values())
            cap = min(cap, max(0.0, soonest - self._wall.monotonic()))
        if any(lk.transport.is_real for lk in self._polled) or self._output_queued():
            cap = min(cap, POLL_WAIT_S)
        return cap

    def _output_queued(self) -> bool:
        return any(transport.pending_output for transport in self._flushers)

    def _settle(self, until: int, slice_end: float | None = None) -> bool:
        """Run events up to ``until`` one instant at a time; True if the run is done early.
        With ``slice_end`` (wall time) it leaves off there, short of ``until``."""
        clock = self.clock
        if slice_end is None and not self._polled and self._predicate is None:
            clock.run_until(until)
            return self._stopping
        while (deadline := clock.next_deadline()) is not None and deadline <= until:
            clock.run_until(deadline)
            self._pump()
            if self._done():
                return True
            if slice_end is not None and self._wall.monotonic() >= slice_end:
                return False  # the slice is spent: commands, descriptors, stop first
        clock.run_until(until)
        return False

    # ----------------------------------------------------------------- pumping

    def _pump(self) -> None:
        """Poll descriptor-less transports, flush queued output, notice closed transports.

        O(1) in the number of TCP connections: closes and backlogs are told by
        the transports themselves; only other kinds of transport are scanned.
        """
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

    def _handle(self, ready: tuple[Collection[int], Collection[int]]) -> Collection[int]:
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
        self._wall.watch(link.fd, read=True, write=bool(pending))

    def _deliver(self, ready: Collection[int]) -> None:
        for fd in ready:
            entry = self._by_fd.get(fd)
            if isinstance(entry, _Link):
                if not entry.paused:
                    self._read(entry)
            elif entry is not None:
                self._accept(entry)

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
        self._wall.forget(entry.fd)
        entry.retry_at = self._wall.monotonic() + entry.backoff
        entry.backoff = min(entry.backoff * 2, ACCEPT_BACKOFF_MAX_S)
        self._retrying[id(entry.listener)] = entry

    def _retry_listeners(self) -> None:
        now = self._wall.monotonic()
        for key, entry in list(self._retrying.items()):
            if entry.retry_at is not None and entry.retry_at <= now:
                del self._retrying[key]
                entry.retry_at = None
                self._wall.watch(entry.fd)

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
