"""The one simulated clock (DESIGN rule 2).

Time is an integer number of microseconds.  Events scheduled for the same time
run in (priority, insertion) order; time never goes back.  Nothing here reads
the wall clock: the real-time runner in ``fieldtwin.runtime`` paces it.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable
from dataclasses import dataclass, field

from fieldtwin.errors import ConfigError

US = 1
MS = 1_000
S = 1_000_000

Callback = Callable[[int], None]


def seconds(value: float) -> int:
    """Simulated seconds -> integer microseconds (rounded to the nearest)."""
    return round(value * S)


@dataclass(order=True, slots=True)
class _Entry:
    time: int
    priority: int
    seq: int
    callback: Callback = field(compare=False)
    cancelled: bool = field(default=False, compare=False)


class Handle:
    """What ``schedule`` returns: cancel it, or ask when it fires."""

    __slots__ = ("_entry",)

    def __init__(self, entry: _Entry) -> None:
        self._entry = entry

    @property
    def time(self) -> int:
        return self._entry.time

    @property
    def active(self) -> bool:
        return not self._entry.cancelled

    def cancel(self) -> None:
        self._entry.cancelled = True


class SimClock:
    """A heap of (time, priority, sequence, callback) in integer microseconds."""

    def __init__(self, start: int = 0) -> None:
        if start < 0:
            raise ConfigError(f"clock start must be >= 0 us, got {start}")
        self._now = start
        self._heap: list[_Entry] = []
        self._seq = itertools.count()
        self._fired = 0

    @property
    def now(self) -> int:
        """Current simulated time in microseconds."""
        return self._now

    @property
    def fired(self) -> int:
        """How many callbacks have run (for benchmarks and tests)."""
        return self._fired

    def schedule(self, at: int, callback: Callback, priority: int = 0) -> Handle:
        """Run ``callback(at)`` at simulated time ``at`` (>= now)."""
        if at < self._now:
            raise ConfigError(f"cannot schedule at {at} us: time is already {self._now} us")
        entry = _Entry(at, priority, next(self._seq), callback)
        heapq.heappush(self._heap, entry)
        return Handle(entry)

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
        while heap and heap[0].cancelled:
            heapq.heappop(heap)
        return heap[0].time if heap else None

    def run_until(self, until: int) -> None:
        """Run every event due at or before ``until``, then set now = until."""
        if until < self._now:
            raise ConfigError(f"time never goes back: {until} us < now {self._now} us")
        heap = self._heap
        while heap and heap[0].time <= until:
            entry = heapq.heappop(heap)
            if entry.cancelled:
                continue
            self._now = entry.time
            entry.cancelled = True
            self._fired += 1
            entry.callback(entry.time)
        self._now = until

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
