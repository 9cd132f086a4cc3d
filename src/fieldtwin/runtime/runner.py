"""The real-time runner: runs the simulated clock, pumps the transports into the cores,
takes commands between instants.  In three parts (docs/architecture.md, "The runner
in parts"): the descriptors (fieldtwin.runtime.reactor), the pacing chosen on every
cycle from what is attached, free, paced to the wall or fast (fieldtwin.runtime.pacing),
and this module: the runs, the stop latch, commands, pause, speed and modes.

``stop()`` is a latch only the run it ends consumes: asked before a run starts (or
during start-up) it ends that run at once; nested runs (a command's ``advance``) see
it and pass it on; the outermost run it ends takes it down; a run that ends otherwise
(its end, its predicate) leaves it for the next.  Every single wait is at most
MAX_WAIT_S, so a stop from another thread is seen within that time.

Commands from other threads come through an inbox (fieldtwin.runtime.inbox) given to
``take_commands``: its wakeup descriptor is watched with the transports, its commands
run on this thread at the start of a cycle, one at a time.  A command may run the
clock itself: such a nested run keeps pumping the transports and takes no other
command until it ends.  ``pause``/``resume`` hold simulated time (the transports are
not read while paused; the inbox still is), ``step`` and ``run_to`` run it by an
amount, paused or not, ``set_speed`` changes the pace without a jump.  ``start_mode``
is their form that holds nothing: the outermost run goes on to the mode's end
between its cycles, taking commands all along; its end is a clock event (the same in
a replay); a new mode or ``pause`` cuts the one in progress.  Catch-up is bounded and
a speed not kept is said (fieldtwin.runtime.pace, ``speed_reached``, ``lagging``).
"""

from __future__ import annotations

from collections.abc import Callable

from fieldtwin.clock import SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.inbox import Inbox
from fieldtwin.runtime.pace import Mode, Modes, Pace, Tempo, check_not_past, check_speed
from fieldtwin.runtime.pacing import Drive, Fast, Free, Pacing, Ticks, Walled
from fieldtwin.runtime.reactor import (
    ACCEPT_BACKOFF_S,
    MAX_WAIT_S,
    OUTPUT_BOUND,
    POLL_WAIT_S,
    AttachTap,
    CloseCallback,
    ConnectCallback,
    DataCallback,
    Reactor,
    Report,
    to_stderr,
)
from fieldtwin.runtime.wall import SystemWall, WallClock
from fieldtwin.transports.base import Listener, Transport


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
        self.report: Report = report or to_stderr
        self._wall: WallClock = wall or SystemWall()
        self._reactor = Reactor(clock, self._wall, self.report)
        self._tempo = Tempo(self.report)
        self._meter = self._tempo.meter
        self._ticks = Ticks()
        drive = Drive(clock, self._wall, self._reactor, self._tempo, self, self._ticks)
        self._free, self._walled, self._fast = Free(drive), Walled(drive), Fast(drive)
        self._predicate: Callable[[], bool] | None = None
        self._stopping = False
        self._inbox: Inbox | None = None
        self._in_command = False  # a command is running: the inbox waits for it
        self._paused = False
        self._stepping = 0  # nested runs of step/run_to: they run while paused
        self._depth = 0  # nested _run calls (a command that runs the clock)
        self._modes = Modes(clock, self._mode_due)  # a step, run-until, power break

    def attach(
        self, transport: Transport, on_data: DataCallback, on_close: CloseCallback | None = None
    ) -> None:
        """Deliver bytes arriving on ``transport`` as ``on_data(data, now)``."""
        self._reactor.attach(transport, on_data, on_close)

    def attach_listener(self, listener: Listener, on_connect: ConnectCallback) -> None:
        """Call ``on_connect(transport, now)`` for every accepted connection."""
        self._reactor.attach_listener(listener, on_connect)

    @property
    def tap(self) -> AttachTap | None:
        """The recording that sees every attachment (``set_tap``), or None."""
        return self._reactor.tap

    def set_tap(self, tap: AttachTap) -> None:
        """From now on ``tap`` sees every attachment; those already made first, in order."""
        self._reactor.set_tap(tap)

    def detach(self, transport_or_listener: Transport | Listener) -> None:
        """Stop pumping it (it stays open); unknown objects are ignored."""
        self._reactor.detach(transport_or_listener)

    def want_precise_waits(self, on: bool) -> None:
        """A core needs its deadlines met on the wall to a fraction of a ms (``on``: issue 15
        item 2, wire-timed RTU replies), or no longer does; some walls cannot (no-op)."""
        self._wall.want_precision(on)

    def hold_pace(self, on: bool) -> None:
        """A server of a real line (``on``) keeps the run paced at ``speed`` while it is
        open, even once its transport has gone (a serial peer that closed)."""
        self._reactor.hold_pace(on)

    @property
    def paced(self) -> bool:
        """A real transport, a listener or a pace holder is there, and speed is a number."""
        return self.speed is not None and self._reactor.holds_pace

    @property
    def watched(self) -> int:
        """Descriptors the runner is watching (links and listeners)."""
        return self._reactor.watched

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
            self._repace(afresh=True)

    def set_speed(self, speed: float | None) -> None:
        """A new speed factor (None: as fast as possible), effective at once, no jump."""
        self.speed = check_speed(speed, "runner speed")
        self._repace(afresh=True)
        self._tempo.lagged_at = float("-inf")

    @property
    def mode(self) -> Mode | None:
        """The mode in progress (its ``name`` and ``until``), or None."""
        return self._modes.current

    def start_mode(
        self, name: str, until_us: int, on_end: Callable[[int, bool], None] | None = None
    ) -> Mode:
        """Run simulated time to ``until_us`` between cycles, paused or not, cutting the mode
        in progress; ``on_end(now, cut)`` at its end (a clock event after the others)."""
        check_not_past(until_us, self.clock.now)
        mode = self._modes.start(name, until_us, on_end)
        self._repace(afresh=True)  # from where the clock stands, paused or not
        return mode

    def end_mode(self) -> None:
        """End the mode in progress now (cut); nothing if none."""
        self._modes.cut()

    def _mode_due(self) -> None:
        if self._paused:  # time holds from now on: the speed reached starts afresh
            self._meter.reset()

    @property
    def speed_reached(self) -> float | None:
        """Simulated s per wall s lately, while time runs (None: held, or not yet known)."""
        return None if self._holding() else self._meter.reached

    @property
    def lagging(self) -> bool:
        """True while the plant does not keep ``speed`` (the pace was moved lately)."""
        return self._tempo.lagging(self._wall.monotonic())

    def _repace(self, afresh: bool = False) -> None:
        """Every run's pace from where the clock stands; ``afresh``: the speed reached too."""
        self._tempo.repace(self._wall.monotonic(), self.clock.now, self.speed or 1.0)
        if afresh:
            self._meter.reset()

    def _holding(self) -> bool:
        """Paused, with an inbox to resume from, outside a step and a command's own run."""
        held = self._paused and self._inbox is not None and not self._stepping
        return held and self._depth == 1 and self._modes.current is None

    def _hold(self) -> None:
        """Paused: no simulated time, no transport read; wait for a command (bounded)."""
        assert self._inbox is not None
        self._inbox.wait(MAX_WAIT_S)
        self._commands()
        if not self._paused:
            self._repace()

    def advance(self, duration_us: int) -> None:
        """Advance simulated time by ``duration_us`` (paced or not, see module docstring)."""
        if duration_us < 0:
            raise ConfigError(f"cannot advance by a negative time ({duration_us} us)")
        if not self._reactor.attached:
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
        self._ticks.start(on_tick, tick_us, self.clock.now)
        try:
            self._run(None, None)
        except KeyboardInterrupt:
            pass
        finally:
            self._ticks.stop()

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
        check_not_past(t_us, self.clock.now)
        self.step(t_us - self.clock.now)

    def stop(self) -> None:
        """End the run in progress after its instant, or the next run at once (a latch)."""
        self._stopping = True

    @property
    def running(self) -> bool:
        """A run (advance, run_until, run_forever) is in progress."""
        return self._depth > 0

    @property
    def stopping(self) -> bool:
        """A stop is asked and not yet taken by the run it ends."""
        return self._stopping

    def _run(self, end: int | None, predicate: Callable[[], bool] | None) -> None:
        if self._in_command and self._inbox is not None:
            self._inbox.flush()  # a command runs the clock: its turn's answers so far leave
        outer = self._predicate
        self._predicate = predicate
        pace = self._tempo.begin(self._wall.monotonic(), self.clock.now, self.speed or 1.0)
        self._fast.restart()  # a run polls before its first instant
        self._depth += 1
        stopped = False  # the stop ended this run (not its end, nor its predicate)
        try:
            while not (predicate is not None and predicate()):
                if (stopped := self._stopping) or not self._cycle(end, pace):
                    break
        except BaseException:
            stopped = self._stopping  # a stop's deadline (KeyboardInterrupt) ended it
            raise
        finally:
            self._depth -= 1
            self._tempo.end()
            self._predicate = outer
            # the stop latch: a nested run (a command's advance) passes it on to the run
            # around it; the outermost run it ended takes it down, and only that run
            if stopped and self._depth == 0:
                self._stopping = False

    def _cycle(self, end: int | None, pace: Pace) -> bool:
        """One wait-and-run step; False once the end is reached."""
        self._commands()
        if self._holding():
            self._hold()
            return True
        self._reactor.pump()
        if self.done():
            return True  # the loop sees why
        deadline = self.clock.next_deadline()
        busy = deadline is not None and (end is None or deadline <= end)
        if not busy and end is not None and self.clock.now >= end:
            return False
        mode = self._modes.current
        if mode is not None and self._depth == 1:  # never past a mode's end in one go
            end = mode.until if end is None else min(end, mode.until)
            busy = deadline is not None and deadline <= end
        self._pacing().step(deadline if busy else end, end, busy, pace)
        self._ticks.due(self.clock.now)
        return True

    def _pacing(self) -> Pacing:
        if self.paced:
            return self._walled
        return self._fast if self._reactor.watched else self._free

    @property
    def every_instant(self) -> bool:
        """A ``run_until`` predicate is checked after every instant."""
        return self._predicate is not None

    def done(self) -> bool:
        """A stop is asked or the run's predicate holds."""
        return self._stopping or (self._predicate is not None and self._predicate())


__all__ = [
    "ACCEPT_BACKOFF_S",
    "MAX_WAIT_S",
    "OUTPUT_BOUND",
    "POLL_WAIT_S",
    "AttachTap",
    "CloseCallback",
    "ConnectCallback",
    "DataCallback",
    "Report",
    "Runner",
]
