"""Which channel the module acquires next, and when (AEM 2.2-4, 3.2-1, 4.1-4).

Each acquisition takes a 100 ms slot.  Normal mode: the 8 channels in
succession from the start of the cycle, channel k in slot k; an inhibited
channel's slot is a 100 ms wait; the cycle restarts every N x 100 ms.
Accelerated mode (OWxy,1,8 = 1): only the enabled channels, one after the
other, so the cycle lasts n x 100 ms.  Pure logic: the module owns the clock.
"""

from __future__ import annotations

from dataclasses import dataclass

from fieldtwin.clock import MS

SLOT_US = 100 * MS  # AEM 2.2-4: 100 ms per channel acquisition
CHANNELS = 8


@dataclass(frozen=True, slots=True)
class Slot:
    """The next acquisition: its start, its channel, and whether a cycle ended first."""

    start: int
    channel: int
    cycle_ended: bool


class Sequencer:
    """The position in the sampling cycle."""

    __slots__ = ("accelerated", "cycle_start", "last", "period_us")

    def __init__(self, period_us: int, accelerated: bool, now: int) -> None:
        self.period_us = period_us
        self.accelerated = accelerated
        self.cycle_start = now
        self.last = -1  # channel of the last slot begun in this cycle

    def restart(self, now: int) -> None:
        """A new cycle starting at ``now`` (Run, or a change of mode)."""
        self.cycle_start = now
        self.last = -1  # channel of the last slot begun in this cycle

    def next_slot(self, now: int, enabled: int) -> Slot | None:
        """The first slot at or after ``now`` for an enabled channel (mask bit i)."""
        if not enabled & 0xFF:
            return None
        if self.accelerated:
            return self._next_accelerated(now, enabled)
        return self._next_normal(now, enabled)

    def begin(self, slot: Slot) -> None:
        self.last = slot.channel

    def _next_accelerated(self, now: int, enabled: int) -> Slot:
        # AEM 2.2-4: only the enabled channels, in succession
        for channel in range(self.last + 1, CHANNELS):
            if enabled >> channel & 1:
                return Slot(now, channel, False)
        self.restart(now)
        return Slot(now, _first(enabled), True)

    def _next_normal(self, now: int, enabled: int) -> Slot:
        ended = False
        if now >= self.cycle_start + self.period_us:  # idle through whole cycles
            cycles = (now - self.cycle_start) // self.period_us
            self.cycle_start += cycles * self.period_us
            self.last, ended = -1, True
        for channel in range(self.last + 1, CHANNELS):
            start = self.cycle_start + channel * SLOT_US
            if enabled >> channel & 1 and start >= now:
                return Slot(start, channel, ended)
        # AEM 3.2-1: the next cycle starts N x 100 ms after this one
        self.cycle_start += self.period_us
        self.last = -1
        first = _first(enabled)
        return Slot(self.cycle_start + first * SLOT_US, first, True)


def _first(enabled: int) -> int:
    return next(c for c in range(CHANNELS) if enabled >> c & 1)
