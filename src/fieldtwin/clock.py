"""The one simulated clock (DESIGN rule 2).

Time is an integer number of microseconds.  Events scheduled for the same time
run in (priority, insertion) order; time never goes back.  Nothing here reads
the wall clock: the real-time runner in ``fieldtwin.runtime`` paces it.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable
from typing import Any

from fieldtwin.errors import ConfigError

US = 1
MS = 1_000
S = 1_000_000

Callback = Callable[[int], None]


def seconds(value: float) -> int:
    """Simulated seconds -> integer microseconds (rounded to the nearest)."""
    return round(value * S)


# A heap entry is a list [time, priority, seq, callback]: lists compare in C, element
# by element, and seq is unique, so the callback is never compared.  A fired or
# cancelled entry has callback None (lazy deletion: it stays in the heap until it
# reaches the top, or until cancelled entries are most of the heap: then the heap is
# compacted, so that an event rescheduled on every edge never bloats it).
_TIME, _CALLBACK = 0, 3
COMPACT_MIN = 64  # no compaction below this many cancelled entries


class Handle:
    """What ``schedule`` returns: cancel it, or ask when it fires."""

    __slots__ = ("_clock", "_entry")

    def __init__(self, clock: SimClock, entry: list[Any]) -> None:
        self._clock = clock
        self._entry = entry

    @property
    def time(self) -> int:
        time: int = self._entry[_TIME]
        return time

    @property
    def active(self) -> bool:
        return self._entry[_CALLBACK] is not None

    @property
    def seq(self) -> int:
        """The entry's sequence number (its place among the events of its instant)."""
        seq: int = self._entry[2]
        return seq

    def cancel(self) -> None:
        entry = self._entry
        if entry[_CALLBACK] is not None:
            entry[_CALLBACK] = None
            self._clock._cancelled_one()


class SimClock:
    """A heap of (time, priority, sequence, callback) in integer microseconds."""

    def __init__(self, start: int = 0) -> None:
        if start < 0:
            raise ConfigError(f"clock start must be >= 0 us, got {start}")
        self._now = start
        self._heap: list[list[Any]] = []
        self._seq = itertools.count()
        # reserve(): the sequence number the next ``schedule`` would take, taken now: an
        # event scheduled later with it (``schedule_as``) runs in the order it would have
        # run in had it been scheduled now
        self.reserve: Callable[[], int] = self._seq.__next__
        self._fired = 0
        self._cancelled = 0  # cancelled entries still in the heap
        # the end of the run_until in progress (-1 outside one, or in run_one): an event
        # may run inline (run_inline) only up to it
        self._until = -1
        # one object per clock that devices share, by name (the TES inputs' beat)
        self.shared: dict[str, Any] = {}
        # told whenever an event is scheduled outside a run_until (between runs: a
        # command, bytes delivered, a test): a parked PLC master task puts its next task
        # back where the unparked run would have it (fieldtwin.tsx.plc, "parking")
        self.outside_watchers: list[Callable[[], None]] = []

    @property
    def now(self) -> int:
        """Current simulated time in microseconds."""
        return self._now

    @property
    def fired(self) -> int:
        """How many callbacks have run (for benchmarks and tests)."""
        return self._fired

    @property
    def pending(self) -> int:
        """Entries in the heap, cancelled ones included (bounded: see COMPACT_MIN)."""
        return len(self._heap)

    def schedule(self, at: int, callback: Callback, priority: int = 0) -> Handle:
        """Run ``callback(at)`` at simulated time ``at`` (>= now)."""
        if at < self._now:
            raise ConfigError(f"cannot schedule at {at} us: time is already {self._now} us")
        entry = [at, priority, next(self._seq), callback]
        heapq.heappush(self._heap, entry)
        if self._until < 0 and self.outside_watchers:
            self._outside()
        return Handle(self, entry)

    def schedule_as(self, at: int, seq: int, callback: Callback) -> Handle:
        """``schedule(at, callback)`` with a sequence number taken by ``reserve``."""
        if at < self._now:
            raise ConfigError(f"cannot schedule at {at} us: time is already {self._now} us")
        entry = [at, 0, seq, callback]
        heapq.heappush(self._heap, entry)
        if self._until < 0 and self.outside_watchers:
            self._outside()
        return Handle(self, entry)

    def _outside(self) -> None:
        for watcher in list(self.outside_watchers):
            watcher()

    def run_inline(self, at: int, seq: int, callback: Callback) -> bool:
        """Run ``callback(at)`` now, from within an event, when that is what the heap
        would do next: ``at`` within the run in progress and before every entry of the
        heap (live or cancelled), so nothing else can run, and nobody outside the run can
        look, between now and ``at``.  The clock moves to ``at`` and counts the event as
        fired; ``seq`` (from ``reserve``) is spent as ``schedule`` would spend it.  False
        (nothing done) otherwise: the caller then schedules it with ``schedule_as``."""
        heap = self._heap
        if at > self._until or (heap and heap[0][0] <= at):
            return False
        self._now = at
        self._fired += 1
        callback(at)
        return True

    def _cancelled_one(self) -> None:
        self._cancelled += 1
        heap = self._heap
        if self._cancelled >= COMPACT_MIN and 2 * self._cancelled > len(heap):
            heap[:] = [e for e in heap if e[_CALLBACK] is not None]
            heapq.heapify(heap)
            self._cancelled = 0

    def call_later(self, delay: int, callback: Callback, priority: int = 0) -> Handle:
        """Run ``callback`` ``delay`` microseconds from now."""
        if delay < 0:
            raise ConfigError(f"delay must be >= 0 us, got {delay}")
        return self.schedule(self._now + delay, callback, priority)

    def cancel(self, handle: Handle) -> None:
        handle.cancel()

    def next_deadline(self) -> int | None:
        """Time of the next live event, or None when nothing is scheduled."""
        heap = self._heap
        while heap and heap[0][_CALLBACK] is None:
            heapq.heappop(heap)
            self._cancelled -= 1
        return heap[0][_TIME] if heap else None

    def next_deadline_besides(self, handle: Handle) -> int | None:
        """Time of the next live event other than ``handle``'s, or None."""
        heap, entry = self._heap, handle._entry
        while heap:
            top = heap[0]
            if top[_CALLBACK] is None:
                heapq.heappop(heap)
                self._cancelled -= 1
            elif top is entry:
                heapq.heappop(heap)
                try:
                    return self.next_deadline()
                finally:
                    heapq.heappush(heap, entry)
            else:
                at: int = top[_TIME]
                return at
        return None

    def run_until(self, until: int) -> None:
        """Run every event due at or before ``until``, then set now = until."""
        if until < self._now:
            raise ConfigError(f"time never goes back: {until} us < now {self._now} us")
        heap = self._heap
        pop = heapq.heappop
        outer, self._until = self._until, until
        try:
            while heap and heap[0][0] <= until:
                entry = pop(heap)
                callback = entry[3]
                if callback is None:
                    self._cancelled -= 1
                    continue
                self._now = at = entry[0]
                entry[3] = None
                self._fired += 1
                callback(at)
        finally:
            self._until = outer
        self._now = until

    def run_one(self) -> bool:
        """Run the next live event alone (not the others of its instant); False when
        nothing is scheduled.  A replay uses it to stand between two recorded events."""
        heap = self._heap
        outer, self._until = self._until, -1  # nothing inline: the caller stands after it
        try:
            return self._run_one(heap)
        finally:
            self._until = outer

    def _run_one(self, heap: list[list[Any]]) -> bool:
        while heap:
            entry = heapq.heappop(heap)
            callback = entry[_CALLBACK]
            if callback is None:
                self._cancelled -= 1
                continue
            self._now = at = entry[_TIME]
            entry[_CALLBACK] = None
            self._fired += 1
            callback(at)
            return True
        return False

    def advance(self, delta: int) -> None:
        """Advance simulated time by ``delta`` microseconds, running due events."""
        if delta < 0:
            raise ConfigError(f"cannot advance by a negative time ({delta} us)")
        self.run_until(self._now + delta)

    def step(self) -> bool:
        """Run the next due event (and any at the same instant). False if idle."""
        deadline = self.next_deadline()
        if deadline is None:
            return False
        self.run_until(deadline)
        return True
