"""Synchronization pulses from outside the module (DEM 1.2-1, 6.3, 7.2).

A pulse source is the external clock (or the PLC output of 5.3-4) that drives
IN-SYN every period.  A module's OUT-SYN repeats its input to at most 32 other
time-stamping modules (7.2 "Maximum 32 modules").  Pulses are instants: the pulse
itself lasts under 10 ms and its rising edge is what the module takes (7.2 note).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from fieldtwin.clock import Handle, SimClock
from fieldtwin.errors import ConfigError

SYNC_OUTPUT_MAX = 32  # DEM 7.2


class PulseSource:
    """Pulses every ``period_us`` from ``start_us`` on; ``silenced`` drops them (a cut wire)."""

    def __init__(
        self, clock: SimClock, period_us: int, start_us: int, target: Callable[[int], None]
    ) -> None:
        if period_us <= 0:
            raise ConfigError(f"sync period must be > 0 us, got {period_us}")
        self.clock = clock
        self.period_us = period_us
        self.target = target
        self.silenced = False
        self.sent = 0
        first = max(start_us, clock.now)
        self._handle: Handle | None = clock.schedule(first, self._fire)

    def _fire(self, now: int) -> None:
        self._handle = self.clock.schedule(now + self.period_us, self._fire)
        if not self.silenced:
            self.sent += 1
            self.target(now)

    def stop(self) -> None:
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None


class SyncReceiver(Protocol):
    rack: int
    slot: int

    def receive_pulse(self, now: int) -> None: ...
