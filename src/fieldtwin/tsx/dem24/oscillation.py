"""Detection of oscillating inputs (DEM 2.3-3, 3.2-1): a hysteresis on transition counts.

An input becomes oscillating when it changes more than N-MAX times within a sliding
T-MAX window; it is normal again once it changes fewer than N-MIN times within the
last T-MIN window (AMB-DEM-11).  Windows are half-open: a transition exactly T ago
has left the window.  The detector is pure: it answers with the next time at which
the return to normal must be checked; the :class:`Monitor` of the 24 inputs schedules
it.  The two states are a machine of one table (:data:`OSCILLATION`, DESIGN rule 4);
the counts decide which input it takes, so an edge costs one window count and a table
lookup only when the state changes.
"""

from __future__ import annotations

import enum
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

from fieldtwin.clock import Handle, S
from fieldtwin.fsm import Machine, Table
from fieldtwin.tsx.dem24.stack import STATE_OSCILLATING


class OscState(enum.Enum):
    NORMAL = "normal"
    OSCILLATING = "oscillating"


class OscEvent(enum.Enum):
    TOO_MANY = "more than N-MAX changes within T-MAX"
    FEW = "fewer than N-MIN changes within T-MIN"


@dataclass(frozen=True, slots=True)
class Thresholds:
    t_max_us: int
    n_max: int
    t_min_us: int
    n_min: int

    @staticmethod
    def from_config(t_max_s: int, n_max: int, t_min_s: int, n_min: int) -> Thresholds:
        return Thresholds(t_max_s * S, n_max, t_min_s * S, n_min)


class Detector:
    """One channel's transition history and oscillation state."""

    __slots__ = ("_times", "declared_at", "machine", "thresholds")

    def __init__(self, thresholds: Thresholds) -> None:
        self.thresholds = thresholds
        self._times: deque[int] = deque(maxlen=max(thresholds.n_max + 1, thresholds.n_min))
        self.machine: Machine[OscState, OscEvent, Detector] = Machine(
            OSCILLATION, OscState.NORMAL, self
        )
        self.declared_at = 0

    @property
    def state(self) -> OscState:
        return self.machine.state

    @property
    def oscillating(self) -> bool:
        return self.machine.state is OscState.OSCILLATING

    def transition(self, t: int) -> bool:
        """Count a transition at ``t``; True when it makes the input oscillating."""
        self._times.append(t)
        th = self.thresholds
        if self.machine.state is OscState.NORMAL and self._count(t, th.t_max_us) > th.n_max:
            self.machine.fire(OscEvent.TOO_MANY, t)  # DEM 3.2-1 "more than N-MAX times"
            return True
        return False

    def _declare(self, t: int) -> None:
        self.declared_at = t

    def _count(self, t: int, window: int) -> int:
        return sum(1 for x in self._times if x > t - window)

    def next_check(self) -> int | None:
        """When an oscillating input can first be normal again (None if normal)."""
        if self.machine.state is OscState.NORMAL:
            return None
        th = self.thresholds
        times = self._times
        # fewer than N-MIN in (t - T-MIN, t] <=> the N-MIN-th latest is <= t - T-MIN
        at = times[-th.n_min] + th.t_min_us if len(times) >= th.n_min else 0
        return max(at, self.declared_at + 1)

    def check(self, t: int) -> bool:
        """True when the input returns to normal at ``t`` (DEM 3.2-1 "less than N-MIN")."""
        if self.machine.state is OscState.OSCILLATING and self._count(
            t, self.thresholds.t_min_us
        ) < (self.thresholds.n_min):
            self.machine.fire(OscEvent.FEW)
            return True
        return False


OSCILLATION: Table[OscState, OscEvent] = Table(
    "DEM oscillating input",
    OscState,
    OscEvent,
    {
        (OscState.NORMAL, OscEvent.TOO_MANY): (Detector._declare, OscState.OSCILLATING),
        (OscState.OSCILLATING, OscEvent.FEW): (None, OscState.NORMAL),
    },
)


Schedule = Callable[[int, Callable[[int], None]], Handle]
ScheduleAs = Callable[[int, int, Callable[[int], None]], Handle]
# what a kept check needs: a sequence number reserved, a schedule with it
KeptChecks = tuple[Callable[[], int], ScheduleAs]


def _no_schedule_as(at: int, seq: int, callback: Callable[[int], None]) -> Handle:
    raise AssertionError("checks are not kept")  # pragma: no cover


class Monitor:
    """The detectors of the 24 inputs under one configuration, and their checks.

    ``normal(channel, now)`` is called when an input is normal again (AMB-DEM-11).
    """

    __slots__ = (
        "_checks",
        "_handles",
        "_normal",
        "_reserve",
        "_schedule",
        "_schedule_as",
        "_wanted",
        "detectors",
        "inline",
        "kept",
    )

    def __init__(
        self,
        thresholds: Thresholds,
        channels: int,
        schedule: Schedule,
        normal: Callable[[int, int], None],
        *,
        inline: bool = True,
        kept: KeptChecks | None = None,
    ) -> None:
        # inline: an edge of an oscillating input is counted and its check armed in
        # judge itself (False, the reference of the tests: transition and _arm)
        self.inline = inline
        self.detectors = [Detector(thresholds) for _ in range(channels)]
        self._handles: list[Handle | None] = [None] * channels
        self._checks = [self._checker(channel) for channel in range(channels)]
        self._schedule = schedule
        self._normal = normal
        # kept (with inline): an edge of an oscillating input leaves the armed check
        # where it is and notes where the reference would re-arm it, with the sequence
        # number it would take (_wanted); the check, when it fires early, moves itself
        # there.  Only the check that the reference runs runs: same instants, same order.
        self.kept = kept is not None
        self._wanted: list[tuple[int, int] | None] = [None] * channels
        if kept is not None:
            self._reserve, self._schedule_as = kept
        else:
            self._reserve = int
            self._schedule_as = _no_schedule_as

    def judge(self, channel: int, edge: int, state: int, now: int = 0) -> int:
        """The state to log for a change at ``edge``: ``state``, 2 = oscillating, or -1
        while oscillating (DEM 2.3-3 "its transitions will no longer be indicated").
        ``now``, the confirmation's instant, is read by a kept check only."""
        detector = self.detectors[channel]
        if not self.inline or detector.machine.state is not OscState.OSCILLATING:
            if detector.transition(edge):
                state = STATE_OSCILLATING
            elif detector.machine.state is OscState.OSCILLATING:
                state = -1
            self._arm(channel)
            return state
        # oscillating: transition(edge) (False), then _arm(channel) with next_check()
        # inlined, the same handle cancelled and the same check scheduled
        times = detector._times
        times.append(edge)
        handles = self._handles
        handle = handles[channel]
        th = detector.thresholds
        n_min = th.n_min
        at = times[-n_min] + th.t_min_us if len(times) >= n_min else 0
        declared = detector.declared_at + 1
        if declared > at:
            at = declared
        if self.kept:  # ``now``: the confirmation's instant
            if at < now:  # as _check_at does
                at = now
            seq = self._reserve()  # where schedule would have taken its number
            # handle.active and handle.time <= at, read from the clock's entry
            if handle is not None and (entry := handle._entry)[3] is not None and entry[0] <= at:
                self._wanted[channel] = (at, seq)  # the armed check moves there
            else:
                if handle is not None:
                    handle.cancel()
                self._wanted[channel] = None
                handles[channel] = self._schedule_as(at, seq, self._checks[channel])
            return -1
        if handle is not None:
            handle.cancel()
        handles[channel] = self._schedule(at, self._checks[channel])
        return -1

    def oscillating(self) -> int:
        """Bit i set while input i is oscillating (DEM 4.2-2 overall-state message)."""
        return sum(int(d.oscillating) << i for i, d in enumerate(self.detectors))

    def check_at(self, channel: int) -> int | None:
        """When the channel's check runs (None: not armed); where a kept check moves."""
        wanted = self._wanted[channel]
        if wanted is not None:
            return wanted[0]
        handle = self._handles[channel]
        return handle.time if handle is not None and handle.active else None

    def stop(self) -> None:
        for handle in self._handles:
            if handle is not None:
                handle.cancel()
        self._handles = [None] * len(self.detectors)
        self._wanted = [None] * len(self.detectors)

    def _checker(self, channel: int) -> Callable[[int], None]:
        return partial(self._check, channel)  # now -> self._check(channel, now)

    def _arm(self, channel: int) -> None:
        handles = self._handles
        handle = handles[channel]
        if handle is not None:
            handle.cancel()
        self._wanted[channel] = None
        at = self.detectors[channel].next_check()
        handles[channel] = None if at is None else self._schedule(at, self._checks[channel])

    def _check(self, channel: int, now: int) -> None:
        wanted = self._wanted[channel]
        if wanted is not None:  # a kept check, early: it moves where the reference has it
            self._wanted[channel] = None
            self._handles[channel] = self._schedule_as(*wanted, self._checks[channel])
            return
        self._handles[channel] = None
        if self.detectors[channel].check(now):
            self._normal(channel, now)
        else:
            self._arm(channel)
