"""How a runner's cycle spends wall time: free, paced to the wall, or fast.

The runner (fieldtwin.runtime.runner) picks one ``Pacing`` per cycle, from what is
attached and its speed, and asks it for one ``step`` towards ``target`` (the next
clock deadline, or the run's end when nothing is due before it):

* ``Free`` - no descriptor attached: events run back to back, memory transports
  are polled after each instant.  With nothing scheduled and no end it waits on
  the wall (time follows at the speed, or x1) instead of spinning.
* ``Walled`` - a real transport or listener is attached (or a server of a real
  line holds the pace) and the speed is a number: simulated time follows the wall
  at the speed.  It sleeps only inside the wall's ``wait``, until the next clock
  deadline mapped to wall time or until bytes arrive.  Bytes that arrive at wall
  time w are given the simulated time they arrived at; events due before it run
  first.  When the clock lags the wall it catches up without sleeping, a slice of
  CATCH_UP_SLICE_S at most per cycle; simulated time never goes back.  A wall's
  ``lead_s`` (precise waits: wire-timed replies) runs a due instant that early.
* ``Fast`` - descriptors attached and ``speed=None``: events run back to back with
  a zero-timeout poll of the descriptors between instants; when no event is due
  before the end, it blocks for data and simulated time follows the wall at x1
  while it waits (a limit of n simulated seconds is at most n wall seconds of
  waiting).  A wall's ``fast_poll_s`` (the system wall's is FAST_POLL_S) asks for
  fewer polls while events run: the descriptors are then polled between two
  instants only once that much wall time has passed since the last poll, and bytes
  that arrived meanwhile get the instant of the poll that finds them.  Every run
  polls before its first instant (``restart``), and after a poll that found bytes
  the next instant polls again.  Between two polls the instants run in one go
  (``_between_polls``): commands, ticks and the end are taken up at the next poll,
  and a ``run_until`` predicate is still checked after every instant.

The three share one ``Drive``: it settles the clock, clamps, waits on the wall, and
holds the run's ``Ticks`` and ``Tempo`` (fieldtwin.runtime.pace: the paces, the speed
reached).  They see the run in progress only through a ``Course`` (is it done, is a
predicate checked after every instant), never the runner's other state.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from typing import Protocol

from fieldtwin.clock import SimClock
from fieldtwin.runtime.pace import CATCH_UP_SLICE_S, Pace, Tempo
from fieldtwin.runtime.reactor import MAX_WAIT_S, Reactor
from fieldtwin.runtime.wall import WallClock


class Course(Protocol):
    """What a pacing step asks of the run in progress (the runner)."""

    @property
    def every_instant(self) -> bool:
        """A predicate is checked after every instant (``run_until``)."""
        ...

    def done(self) -> bool:
        """A stop is asked or the run's predicate holds."""
        ...


class Ticks:
    """``run_forever``'s ticks: ``on_tick(now)`` about every ``every`` simulated µs.  They
    are not clock events: they never keep the clock busy."""

    def __init__(self) -> None:
        self.on_tick: Callable[[int], None] | None = None
        self.every = 0  # 0: no ticks (outside run_forever)
        self.next = 0  # simulated time of the next tick

    def start(self, on_tick: Callable[[int], None] | None, every: int, now: int) -> None:
        self.on_tick, self.every, self.next = on_tick, every, now + every

    def stop(self) -> None:
        self.every = 0

    def soonest(self, target: int | None) -> int | None:
        """``target``, or the next tick if it comes first (so paced ticks are on time)."""
        if not self.every:
            return target
        return self.next if target is None else min(target, self.next)

    def lagged(self, now: int) -> None:
        """The pace was moved: the ticks come on the wall too."""
        self.next = min(self.next, now)

    def due(self, now: int) -> None:
        """Tick if a tick is due (once, however many were missed)."""
        if not self.every or now < self.next:
            return
        self.next += self.every * ((now - self.next) // self.every + 1)
        if self.on_tick is not None:
            self.on_tick(now)


class Pacing(Protocol):
    """One way to spend a cycle's wall time (see the module docstring)."""

    def step(self, target: int | None, end: int | None, busy: bool, pace: Pace) -> None:
        """Wait, deliver and run instants towards ``target`` (``busy``: an event is due
        at it, before ``end``), never past ``end``."""
        ...


class Drive:
    """What the pacings share: the clock, the wall, the descriptors, the speed meter."""

    def __init__(
        self,
        clock: SimClock,
        wall: WallClock,
        reactor: Reactor,
        tempo: Tempo,
        course: Course,
        ticks: Ticks,
    ) -> None:
        self.clock = clock
        self.ticks = ticks
        self.wall = wall
        self.reactor = reactor
        self.tempo = tempo
        self.meter = tempo.meter
        self.course = course

    def settle(self, until: int, slice_end: float | None = None) -> bool:
        """Run events up to ``until`` one instant at a time; True if the run is done early.
        With ``slice_end`` (wall time) it leaves off there, short of ``until``."""
        clock, course = self.clock, self.course
        if slice_end is None and not self.reactor.polled and not course.every_instant:
            clock.run_until(until)
            return course.done()
        while (deadline := clock.next_deadline()) is not None and deadline <= until:
            clock.run_until(deadline)
            self.reactor.pump()
            if course.done():
                return True
            if slice_end is not None and self.wall.monotonic() >= slice_end:
                return False  # the slice is spent: commands, descriptors, stop first
        clock.run_until(until)
        return False

    def clamp(self, sim: int, end: int | None) -> int:
        """Never before now (time never goes back), never past the end."""
        sim = max(sim, self.clock.now)
        return sim if end is None else min(sim, end)

    def wait(self, timeout: float) -> Collection[int]:
        """Wait on the wall (at most the descriptors' cap); the readable descriptors."""
        return self.reactor.handle(self.wall.wait(min(timeout, self.reactor.wait_cap())))


class Free:
    """No descriptor: events back to back; idle, time follows the wall at the speed."""

    def __init__(self, drive: Drive) -> None:
        self.drive = drive

    def step(self, target: int | None, end: int | None, busy: bool, pace: Pace) -> None:
        drive = self.drive
        if target is not None:
            # never past the next tick: a parked master task (fieldtwin.tsx.plc) leaves
            # long gaps between instants, and the ticks still come on their time
            drive.settle(drive.ticks.soonest(target))  # type: ignore[arg-type]
            return
        # nothing scheduled, nothing real, no end (run_forever): wait on the wall
        now, speed = drive.clock.now, pace.speed
        wake = drive.ticks.soonest(end)
        timeout = MAX_WAIT_S if wake is None else (wake - now) / 1_000_000 / speed
        start = drive.wall.monotonic()
        drive.wait(timeout)
        woke = drive.wall.monotonic()
        drive.settle(drive.clamp(drive.clock.now + round((woke - start) * speed * 1e6), end))
        drive.meter.sample(woke, drive.clock.now)


class Walled:
    """Simulated time follows the wall at the pace's speed."""

    def __init__(self, drive: Drive) -> None:
        self.drive = drive

    def step(self, target: int | None, end: int | None, busy: bool, pace: Pace) -> None:
        drive = self.drive
        wall = drive.wall
        target = drive.ticks.soonest(target)  # paced ticks are on time
        lead = wall.lead_s  # bytes that arrive are still timed by the wall as it is
        if target is None:
            timeout = MAX_WAIT_S
        else:
            timeout = min(max(0.0, pace.wall_at(target) - lead - wall.monotonic()), MAX_WAIT_S)
        ready = drive.wait(timeout)
        woke = wall.monotonic()
        reached = drive.clamp(pace.sim_at(woke), end)
        if ready:  # catch up (a slice at most), then the bytes at the time reached
            if not drive.settle(reached, woke + CATCH_UP_SLICE_S):
                drive.reactor.deliver(ready)
        elif target is None:
            drive.settle(reached)
        else:
            if lead and woke + lead >= pace.wall_at(target):
                reached = max(reached, drive.clamp(target, end))
            drive.settle(min(target, reached))  # one instant at most
        if not drive.tempo.kept(woke, drive.clock.now, pace):  # the pace moved
            drive.ticks.lagged(drive.clock.now)  # the ticks come on the wall too


class Fast:
    """Events back to back, the descriptors polled between instants (every
    ``fast_poll_s`` of wall time at most while busy); idle, time follows at x1."""

    def __init__(self, drive: Drive) -> None:
        self.drive = drive
        self.poll_s = drive.wall.fast_poll_s  # the least wall time between two busy polls
        self.next_poll = float("-inf")  # wall time of the next such poll

    def restart(self) -> None:
        """A run begins: it polls before its first instant."""
        self.next_poll = float("-inf")

    def step(self, target: int | None, end: int | None, busy: bool, pace: Pace) -> None:
        if busy:
            self._busy(target, end)
        else:
            self._idle(target, end)

    def _busy(self, target: int | None, end: int | None) -> None:
        drive = self.drive
        wall = drive.wall
        target = drive.ticks.soonest(target)  # the ticks on their time (as in Free)
        if self.poll_s:
            now_wall = wall.monotonic()
            if now_wall < self.next_poll:  # polled less than poll_s ago
                self._between_polls(target, end)
                return
            self.next_poll = now_wall + self.poll_s
        ready = drive.reactor.handle(wall.wait(0))
        drive.meter.sample(wall.monotonic(), drive.clock.now)
        if ready:
            self.next_poll = float("-inf")  # while bytes keep coming: every instant
            drive.reactor.deliver(ready)  # arrived while the clock stood at now
        elif target is not None:
            drive.settle(target)

    def _idle(self, target: int | None, end: int | None) -> None:
        """Wait for a peer, letting simulated time follow the wall at x1."""
        drive = self.drive
        wall = drive.wall
        start = wall.monotonic()
        wake = drive.ticks.soonest(target)
        timeout = MAX_WAIT_S if wake is None else (wake - drive.clock.now) / 1_000_000
        ready = drive.wait(timeout)
        woke = wall.monotonic()
        reached = drive.clamp(drive.clock.now + round((woke - start) * 1_000_000), end)
        if not drive.settle(reached) and ready:
            drive.reactor.deliver(ready)
        drive.meter.sample(woke, drive.clock.now)

    def _between_polls(self, target: int | None, end: int | None) -> None:
        """No poll due: run instants back to back (each settled as a cycle would) until
        ``poll_s`` of wall time has passed since the last poll, the end, the next tick
        or a stop; the cycle around then polls, ticks, takes commands."""
        drive = self.drive
        clock, wall = drive.clock, drive.wall
        limit = drive.ticks.soonest(end)
        next_poll = self.next_poll
        while target is not None:
            if drive.settle(target):
                return
            target = clock.next_deadline()
            if target is None or (limit is not None and target > limit):
                return
            if wall.monotonic() >= next_poll:
                return


__all__ = ["Course", "Drive", "Fast", "Free", "Pacing", "Ticks", "Walled"]
