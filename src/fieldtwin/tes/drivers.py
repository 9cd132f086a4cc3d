"""Drive a digital input from a discrete signal, edge by edge (DESIGN rule 3)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from fieldtwin.clock import Handle, SimClock


class DiscreteSource(Protocol):
    """Anything with the fieldtwin.signals DiscreteSignal methods."""

    def value_at(self, t_us: int) -> bool: ...

    def next_change(self, t_us: int) -> int | None: ...


class DiscreteDriver:
    """Applies ``signal`` at start, then at each of its changes."""

    def __init__(
        self, clock: SimClock, signal: DiscreteSource, apply: Callable[[bool, int], None]
    ) -> None:
        self._clock = clock
        self._signal = signal
        self._apply = apply
        self._handle: Handle | None = None

    def start(self, now: int) -> None:
        self._step(now)

    def stop(self) -> None:
        if self._handle is not None:
            self._handle.cancel()
            self._handle = None

    def _step(self, now: int) -> None:
        self._handle = None
        self._apply(bool(self._signal.value_at(now)), now)
        at = self._signal.next_change(now)
        if at is not None:
            self._handle = self._clock.schedule(max(at, now + 1), self._step)
