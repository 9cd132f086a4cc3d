"""IN-SYN, the synchronization input, and its 500 us filter (DEM 1.2-1, 7.2).

The input has a level: a bool, or volts judged like a discrete input of the module
(7.2 "Synchronization input: identical characteristics to 24-Input modules"),
whatever their sign (7.2 "accepts a positive or negative pulse").  A pulse counts
once the input has been active for the 500 us filter (1.2-1 "The synchronization
input is filtered at 500 microseconds"); a shorter pulse is ignored.  A pulse that
counts is taken at the end of the filter and refers to its leading edge, the instant
the time reference marks (7.2 note: the rising edge takes under 500 us).  Longer
pulses count once, at their leading edge; the "< 10 ms" of the 7.2 note is what the
emitter must give, not a second filter (docs/manual-notes.md).

The three states are one machine (:data:`SYNC_INPUT`, DESIGN rule 4).  A pulse costs
three clock events (leading edge, end of filter, trailing edge); the 24 inputs pay
nothing for it.
"""

from __future__ import annotations

import enum
from collections.abc import Callable

from fieldtwin.clock import MS, Handle, SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.fsm import Machine, Table
from fieldtwin.signals import DiscreteSignal
from fieldtwin.tsx.dem24.inputs import Thresholds

SYNC_FILTER_US = 500  # DEM 1.2-1 "The synchronization input is filtered at 500 microseconds"
SYNC_PULSE_US = 5 * MS  # a conforming pulse: over the 500 us filter, under the 10 ms of 7.2


class SyncLevel(enum.Enum):
    REST = "at rest"
    FILTERING = "pulse being filtered"
    HELD = "pulse taken, input still active"


class SyncEdge(enum.Enum):
    LEADING = "leading edge"
    TRAILING = "trailing edge"
    FILTERED = "active for the filter time"


class SyncInput:
    """IN-SYN: ``take(leading_edge)`` for each pulse that passes the filter.

    ``repeat(active, t)`` sees every change of the level, filtered or not: OUT-SYN
    "is an amplification of the synchronization input" (1.2-1).
    """

    def __init__(
        self,
        clock: SimClock,
        thresholds: Thresholds,
        take: Callable[[int], None],
        repeat: Callable[[bool, int], None],
    ) -> None:
        self.clock = clock
        self.thresholds = thresholds
        self._take = take
        self._repeat = repeat
        self.machine: Machine[SyncLevel, SyncEdge, SyncInput] = Machine(
            SYNC_INPUT, SyncLevel.REST, self
        )
        self.active = False  # the level at the terminals, after the thresholds
        self.leading_edge = 0
        self.taken = 0  # pulses that passed the filter
        self.ignored = 0  # pulses shorter than the filter
        self._filter: Handle | None = None
        self._signal: DiscreteSignal | None = None
        self._signal_handle: Handle | None = None

    @property
    def state(self) -> SyncLevel:
        return self.machine.state

    def set_level(self, value: bool | float, t: int) -> None:
        """The input now: a bool, or volts of either sign (7.2)."""
        if isinstance(value, bool):
            active = value
        elif isinstance(value, int | float) and value == value and abs(value) != float("inf"):
            active = self.thresholds.judge(abs(float(value)), self.active)
        else:
            raise ConfigError(f"sync input: {value!r} is not a bool or a voltage")
        if active == self.active:
            return
        self.active = active
        self.machine.fire(SyncEdge.LEADING if active else SyncEdge.TRAILING, t)
        self._repeat(active, t)

    def attach(self, signal: DiscreteSignal | None) -> None:
        """Drive the input from a discrete signal (its edges, as they come); None takes
        the signal off and leaves the input at rest."""
        if self._signal_handle is not None:
            self._signal_handle.cancel()
            self._signal_handle = None
        self._signal = signal
        if signal is not None:
            self._follow(self.clock.now)
        elif self.active:
            self.set_level(False, self.clock.now)

    def _follow(self, t: int) -> None:
        signal = self._signal
        assert signal is not None
        self.set_level(bool(signal.value_at(t)), t)
        nxt = signal.next_change(t)
        self._signal_handle = None if nxt is None else self.clock.schedule(nxt, self._follow)

    def pulse(self, t: int, width_us: int = SYNC_PULSE_US) -> None:
        """A pulse of ``width_us`` from ``t`` on (pulses closer than their width merge)."""
        check_width(width_us)
        self.set_level(True, t)
        self.clock.schedule(t + width_us, lambda now: self.set_level(False, now))

    # --- the actions of the table ------------------------------------------------

    def _start_filter(self, t: int) -> None:
        self.leading_edge = t
        self._filter = self.clock.schedule(t + SYNC_FILTER_US, self._filtered)

    def _filtered(self, now: int) -> None:
        self._filter = None
        self.machine.fire(SyncEdge.FILTERED, now)

    def _reject(self, t: int) -> None:
        if self._filter is not None:
            self._filter.cancel()
            self._filter = None
        self.ignored += 1  # DEM 1.2-1: shorter than the 500 us filter

    def _accept(self, now: int) -> None:
        self.taken += 1
        self._take(self.leading_edge)


def check_width(width_us: int) -> int:
    if isinstance(width_us, bool) or not isinstance(width_us, int) or width_us <= 0:
        raise ConfigError(f"sync pulse width {width_us!r} not allowed (allowed: > 0 us)")
    return width_us


SYNC_INPUT: Table[SyncLevel, SyncEdge] = Table(
    "DEM synchronization input",
    SyncLevel,
    SyncEdge,
    {
        (SyncLevel.REST, SyncEdge.LEADING): (SyncInput._start_filter, SyncLevel.FILTERING),
        (SyncLevel.FILTERING, SyncEdge.TRAILING): (SyncInput._reject, SyncLevel.REST),
        (SyncLevel.FILTERING, SyncEdge.FILTERED): (SyncInput._accept, SyncLevel.HELD),
        (SyncLevel.HELD, SyncEdge.TRAILING): (None, SyncLevel.REST),
    },
)
