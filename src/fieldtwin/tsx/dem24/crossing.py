"""When a voltage signal crosses the IEC 61131-2 type 1 limits of an input (DEM 7.2).

A module cycle is under a millisecond (DEM 7.2 "Module cycle time"), so an input is
judged continuously, not only at a signal's breakpoints: a ramp that passes 15 V
between two breakpoints switches the input at that microsecond.  The next event of
an analog signal is the earliest of its next breakpoint and the first instant at
which the input would change:

- signals that are straight lines between breakpoints (constants, steps, ramps,
  piecewise-linear tables, squares, and sums or noise over them) are probed once
  just before the next breakpoint and bisected to the microsecond when they cross;
- a sine is solved: the candidate instants where it meets the threshold, then
  bisection to the microsecond;
- any other signal is sampled every millisecond (the module cycle) up to a
  horizon, and a crossing is bisected to the microsecond.

The crossing is judged with the hysteresis of :meth:`Thresholds.judge`: an input at 0
waits for ON (>= on_min), an input at 1 for OFF (<= off_max).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Protocol

from fieldtwin.clock import MS, S
from fieldtwin.signals import (
    AnalogSignal,
    Constant,
    Noise,
    PiecewiseLinear,
    Ramp,
    Sine,
    Square,
    Step,
    Sum,
)

HORIZON_US = 1 * S  # a sampled signal is looked at one second ahead at a time
SAMPLE_US = MS  # the module cycle, under a millisecond (DEM 7.2)


class Limits(Protocol):
    off_max: float
    on_min: float


Crossed = Callable[[float], bool]


def crossed_test(limits: Limits, level: bool) -> tuple[Crossed, float]:
    """The test that tells the input changes, and the threshold it watches."""
    if level:
        return (lambda v: v <= limits.off_max), limits.off_max
    return (lambda v: v >= limits.on_min), limits.on_min


def next_event(signal: AnalogSignal, t: int, level: bool, limits: Limits) -> int | None:
    """The next time > ``t`` the input must be judged again (None: never)."""
    crossed, threshold = crossed_test(limits, level)
    breakpoint_ = signal.next_change(t)
    if _linear(signal):
        if breakpoint_ is None:
            return None  # constant from now on
        probe = breakpoint_ - 1
        if probe > t and crossed(signal.value_at(probe)):
            return _bisect(signal, t, probe, crossed)
        return breakpoint_
    if isinstance(signal, Sine):
        return _sine(signal, t, crossed, threshold)
    return _sampled(signal, t, breakpoint_, crossed)


def _linear(signal: AnalogSignal) -> bool:
    """Straight lines between breakpoints (DESIGN rule 3: signals say when they change)."""
    if isinstance(signal, Constant | Step | Ramp | PiecewiseLinear | Square):
        return True
    if isinstance(signal, Sum):
        return all(_linear(term) for term in signal.terms)
    if isinstance(signal, Noise):
        return _linear(signal.base)
    return False


def _bisect(signal: AnalogSignal, lo: int, hi: int, crossed: Crossed) -> int:
    """First microsecond in (lo, hi] that is crossed; ``lo`` is not, ``hi`` is."""
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if crossed(signal.value_at(mid)):
            hi = mid
        else:
            lo = mid
    return hi


def _sampled(signal: AnalogSignal, t: int, breakpoint_: int | None, crossed: Crossed) -> int:
    limit = t + HORIZON_US if breakpoint_ is None else min(breakpoint_, t + HORIZON_US)
    previous = t
    sample = t + SAMPLE_US
    while sample < limit:
        if crossed(signal.value_at(sample)):
            return _bisect(signal, previous, sample, crossed)
        previous, sample = sample, sample + SAMPLE_US
    if limit - 1 > previous and crossed(signal.value_at(limit - 1)):
        return _bisect(signal, previous, limit - 1, crossed)
    return limit  # judged again there (a breakpoint, or the end of the horizon)


def _sine(signal: Sine, t: int, crossed: Crossed, threshold: float) -> int | None:
    if signal.amplitude == 0:
        return None
    c = (threshold - signal.offset) / signal.amplitude
    if abs(c) > 1:
        return None  # the sine never reaches the threshold
    period = signal.period_us
    base = math.asin(c)
    phase = math.radians(signal.phase_deg)
    first_period = t - t % period
    candidates = []
    for angle in (base, math.pi - base):
        offset = (angle - phase) / (2 * math.pi) % 1.0 * period
        for k in range(3):
            at = first_period + offset + (k - 1) * period
            if at > t - 2:
                candidates.append(at)
    for at in sorted(candidates):
        if at > t + period + 2:
            break
        for probe in range(max(t + 1, math.floor(at) - 2), math.ceil(at) + 3):
            if crossed(signal.value_at(probe)):
                lo = max(t, probe - 1)
                return (
                    probe if crossed(signal.value_at(lo)) else _bisect(signal, lo, probe, crossed)
                )
    return None  # it only touches the threshold: never crosses
