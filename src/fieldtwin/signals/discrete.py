"""Discrete signals: a bool at each simulated time (us) and the exact time of its next edge.

``next_change(t)`` is the first time > t at which ``value_at`` differs from
``value_at(t)`` (None: never again), so a device schedules the edge on the clock.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import dataclass, field

from fieldtwin.errors import ConfigError
from fieldtwin.signals.base import UniformStream, check_fraction, check_period


@dataclass(frozen=True, slots=True)
class DiscreteConstant:
    value: bool

    def value_at(self, t: int) -> bool:
        return bool(self.value)

    def next_change(self, t: int) -> int | None:
        return None


@dataclass(frozen=True, slots=True)
class PulseTrain:
    """From ``start_us`` on, ``duty`` of each period is True; False before ``start_us``.

    ``high_first``: each period opens with its True part (else it ends with it).
    """

    period_us: int
    duty: float = 0.5
    start_us: int = 0
    high_first: bool = True

    def __post_init__(self) -> None:
        check_period("period", self.period_us)
        check_fraction("duty", self.duty)

    @property
    def high_us(self) -> int:
        return round(self.duty * self.period_us)

    def _rise(self) -> int:
        """Offset of the rising edge within a period."""
        return 0 if self.high_first else self.period_us - self.high_us

    def value_at(self, t: int) -> bool:
        if t < self.start_us or self.high_us == 0:
            return False
        phase = (t - self.start_us) % self.period_us
        rise = self._rise()
        return rise <= phase < rise + self.high_us

    def next_change(self, t: int) -> int | None:
        high, period = self.high_us, self.period_us
        if high == 0:
            return None
        if t < self.start_us:
            return self.start_us + (0 if high == period else self._rise())
        if high == period:
            return None
        phase = (t - self.start_us) % period
        edges = (0, high, period) if self.high_first else (period - high, period)
        return t - phase + next(edge for edge in edges if edge > phase)


def _check_times(times: Sequence[int]) -> tuple[int, ...]:
    for index, t in enumerate(times):
        if isinstance(t, bool) or not isinstance(t, int):
            raise ConfigError(f"edge {index}: time {t!r} must be whole microseconds")
        if index and t <= times[index - 1]:
            raise ConfigError(
                f"edge {index}: time {t} us is not after {times[index - 1]} us"
                " (edge times must increase)"
            )
    return tuple(times)


@dataclass(frozen=True, slots=True)
class Edges:
    """``initial`` until the first time of ``times_us``; each time toggles the value."""

    initial: bool
    times_us: Sequence[int]

    def __post_init__(self) -> None:
        object.__setattr__(self, "times_us", _check_times(self.times_us))

    @classmethod
    def from_list(cls, changes: Sequence[tuple[int, bool]], *, initial: bool = False) -> Edges:
        """[(t_us, value), ...]: the value from each time on; repeats are not edges."""
        times: list[int] = []
        current = initial
        for index, (t, value) in enumerate(changes):
            if index and t <= changes[index - 1][0]:
                raise ConfigError(f"change {index}: time {t} us is not after the previous one")
            if bool(value) != current:
                times.append(t)
                current = bool(value)
        return cls(initial, times)

    def value_at(self, t: int) -> bool:
        return bool(self.initial) ^ (bisect_right(self.times_us, t) % 2 == 1)

    def next_change(self, t: int) -> int | None:
        index = bisect_right(self.times_us, t)
        return self.times_us[index] if index < len(self.times_us) else None

    def value_and_next(self, t: int) -> tuple[bool, int | None]:
        """``(value_at(t), next_change(t))`` with one search of the times."""
        times = self.times_us
        index = bisect_right(times, t)
        return bool(self.initial) ^ (index % 2 == 1), times[index] if index < len(times) else None


REACH_AHEAD = 15  # edges drawn ahead of the one a search needs (a cache: same values)


@dataclass(frozen=True, slots=True)
class RandomEdges:
    """Edges at random intervals: ``min_interval_us`` plus an exponential draw.

    The mean interval is ``mean_interval_us``.  Interval k is a hash of (seed, k), so
    the edges are the same whatever order the times are asked in; the edge times
    found so far are kept (an append-only cache, not a state).
    """

    seed: int
    mean_interval_us: int
    min_interval_us: int = 1_000
    initial: bool = False
    _edges: list[int] = field(default_factory=list, init=False, repr=False, compare=False)
    _uniform: UniformStream = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_period("min interval", self.min_interval_us)
        check_period("mean interval", self.mean_interval_us)
        if self.mean_interval_us < self.min_interval_us:
            raise ConfigError(
                f"mean interval {self.mean_interval_us} us is below the minimum interval"
                f" {self.min_interval_us} us (allowed mean >= min)"
            )
        object.__setattr__(self, "_uniform", UniformStream(self.seed, "edges"))

    def _interval(self, index: int) -> int:
        spread = self.mean_interval_us - self.min_interval_us
        draw = -math.log(self._uniform(index)) * spread
        return self.min_interval_us + round(draw)

    def _reach(self, t: int) -> None:
        """Extend the edge list past ``t``."""
        edges = self._edges
        last = edges[-1] if edges else 0
        if edges and last > t:
            return
        # _interval inlined: the same draws, the same arithmetic
        minimum, spread = self.min_interval_us, self.mean_interval_us - self.min_interval_us
        draw, log, append = self._uniform, math.log, edges.append
        index = len(edges)
        while not index or last <= t:
            last += minimum + round(-log(draw(index)) * spread)
            append(last)
            index += 1
        for ahead in range(index, index + REACH_AHEAD):  # a few more: fewer calls
            last += minimum + round(-log(draw(ahead)) * spread)
            append(last)

    def value_at(self, t: int) -> bool:
        self._reach(t)
        return bool(self.initial) ^ (bisect_right(self._edges, t) % 2 == 1)

    def next_change(self, t: int) -> int | None:
        self._reach(t)
        return self._edges[bisect_right(self._edges, t)]

    def value_and_next(self, t: int) -> tuple[bool, int | None]:
        """``(value_at(t), next_change(t))`` with one search of the edges."""
        edges = self._edges
        if not edges or edges[-1] <= t:
            self._reach(t)
        index = bisect_right(edges, t)
        return bool(self.initial) ^ (index % 2 == 1), edges[index]
