"""Analog signals: a float at each simulated time (us), in the unit the device expects.

Each ``next_change(t)`` gives the next breakpoint after ``t`` (see
:class:`fieldtwin.signals.base.AnalogSignal`).  Constructors check their arguments
and raise ConfigError naming the one that is wrong.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from fieldtwin.errors import ConfigError
from fieldtwin.signals.base import AnalogSignal, check_finite, check_fraction, check_period, gauss


def _earliest(*times: int | None) -> int | None:
    known = [t for t in times if t is not None]
    return min(known) if known else None


@dataclass(frozen=True, slots=True)
class Constant:
    value: float

    def __post_init__(self) -> None:
        check_finite("value", self.value)

    def value_at(self, t: int) -> float:
        return float(self.value)

    def next_change(self, t: int) -> int | None:
        return None


@dataclass(frozen=True, slots=True)
class Step:
    """``before`` until ``at_us``, ``after`` from ``at_us`` on."""

    before: float
    after: float
    at_us: int

    def __post_init__(self) -> None:
        check_finite("before", self.before)
        check_finite("after", self.after)

    def value_at(self, t: int) -> float:
        return float(self.before if t < self.at_us else self.after)

    def next_change(self, t: int) -> int | None:
        return self.at_us if t < self.at_us and self.before != self.after else None


@dataclass(frozen=True, slots=True)
class Ramp:
    """``start`` until ``t0_us``, linear to ``end`` over ``duration_us``, then ``end``."""

    start: float
    end: float
    t0_us: int
    duration_us: int

    def __post_init__(self) -> None:
        check_finite("start", self.start)
        check_finite("end", self.end)
        if self.duration_us < 0:
            raise ConfigError(f"duration must be >= 0 us, got {self.duration_us}")

    def value_at(self, t: int) -> float:
        if t < self.t0_us:
            return float(self.start)
        if t >= self.t0_us + self.duration_us:
            return float(self.end)
        fraction = (t - self.t0_us) / self.duration_us
        return self.start + (self.end - self.start) * fraction

    def next_change(self, t: int) -> int | None:
        if self.start == self.end:
            return None
        if t < self.t0_us:
            return self.t0_us
        end = self.t0_us + self.duration_us
        return end if t < end else None


@dataclass(frozen=True, slots=True)
class Sine:
    """``offset + amplitude * sin(2 pi t / period + phase)``."""

    offset: float
    amplitude: float
    period_us: int
    phase_deg: float = 0.0

    def __post_init__(self) -> None:
        check_finite("offset", self.offset)
        check_finite("amplitude", self.amplitude)
        check_period("period", self.period_us)
        check_finite("phase", self.phase_deg)

    def value_at(self, t: int) -> float:
        angle = 2.0 * math.pi * (t % self.period_us) / self.period_us
        return self.offset + self.amplitude * math.sin(angle + math.radians(self.phase_deg))

    def next_change(self, t: int) -> int | None:
        return None  # smooth for ever: no breakpoint


@dataclass(frozen=True, slots=True)
class Square:
    """``high`` for the first ``duty`` of each period (from t = 0), ``low`` for the rest."""

    low: float
    high: float
    period_us: int
    duty: float = 0.5

    def __post_init__(self) -> None:
        check_finite("low", self.low)
        check_finite("high", self.high)
        check_period("period", self.period_us)
        check_fraction("duty", self.duty)

    @property
    def high_us(self) -> int:
        return round(self.duty * self.period_us)

    def value_at(self, t: int) -> float:
        return float(self.high if t % self.period_us < self.high_us else self.low)

    def next_change(self, t: int) -> int | None:
        if self.low == self.high or self.high_us in (0, self.period_us):
            return None
        phase = t % self.period_us
        start = t - phase
        return start + self.high_us if phase < self.high_us else start + self.period_us


@dataclass(frozen=True, slots=True)
class PiecewiseLinear:
    """Straight lines between (t_us, value) points; the end values hold outside.

    Two points at the same time make a jump (the second value holds from then on).
    """

    points: Sequence[tuple[int, float]]
    _times: tuple[int, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        points = tuple((t, float(v)) for t, v in self.points)
        if not points:
            raise ConfigError("a piecewise-linear signal needs at least one (time, value) point")
        for index, (t, v) in enumerate(points):
            if isinstance(t, bool) or not isinstance(t, int):
                raise ConfigError(f"point {index}: time {t!r} must be whole microseconds")
            check_finite(f"point {index} value", v)
            if index and t < points[index - 1][0]:
                raise ConfigError(f"point {index}: time {t} us goes back (times must not decrease)")
            if index > 1 and t == points[index - 2][0]:
                raise ConfigError(f"point {index}: three points at {t} us (at most two, a jump)")
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "_times", tuple(t for t, _ in points))

    @classmethod
    def from_csv(cls, path: Path | str) -> PiecewiseLinear:
        """Rows ``time_s,value`` (header optional); see :mod:`fieldtwin.signals.table`."""
        from fieldtwin.signals.table import read_points

        points = read_points(Path(path))
        try:
            return cls(points)
        except ConfigError as exc:
            raise ConfigError(f"{path}: {exc}") from None

    def value_at(self, t: int) -> float:
        points = self.points
        index = bisect_right(self._times, t)
        if index == 0:
            return points[0][1]
        if index == len(points):
            return points[-1][1]
        (t1, v1), (t2, v2) = points[index - 1], points[index]
        return v1 + (v2 - v1) * (t - t1) / (t2 - t1)

    def next_change(self, t: int) -> int | None:
        index = bisect_right(self._times, t)
        return self._times[index] if index < len(self._times) else None


@dataclass(frozen=True, slots=True)
class Noise:
    """``base`` plus gaussian noise (standard deviation ``sigma``) held per sample period.

    Sample k covers [k * period, (k + 1) * period); its draw is a hash of (seed, k),
    so the value at t does not depend on what was asked before.
    """

    base: AnalogSignal
    sigma: float
    seed: int
    sample_period_us: int = 1_000

    def __post_init__(self) -> None:
        check_finite("sigma", self.sigma)
        if self.sigma < 0:
            raise ConfigError(f"sigma must be >= 0, got {self.sigma}")
        check_period("sample period", self.sample_period_us)

    def value_at(self, t: int) -> float:
        sample = t // self.sample_period_us
        return self.base.value_at(t) + self.sigma * gauss(self.seed, "noise", sample)

    def next_change(self, t: int) -> int | None:
        if self.sigma == 0:
            return self.base.next_change(t)
        boundary = (t // self.sample_period_us + 1) * self.sample_period_us
        return _earliest(self.base.next_change(t), boundary)


@dataclass(frozen=True, slots=True)
class Sum:
    """The sum of several analog signals (an offset, a ripple on a ramp...)."""

    terms: Sequence[AnalogSignal]

    def __post_init__(self) -> None:
        if not self.terms:
            raise ConfigError("a sum needs at least one signal")
        object.__setattr__(self, "terms", tuple(self.terms))

    def value_at(self, t: int) -> float:
        return sum(term.value_at(t) for term in self.terms)

    def next_change(self, t: int) -> int | None:
        return _earliest(*(term.next_change(t) for term in self.terms))
