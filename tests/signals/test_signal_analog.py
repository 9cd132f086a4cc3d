"""Analog signals: values, breakpoints, seeded noise (fieldtwin.signals.analog)."""

from __future__ import annotations

import math
import statistics

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.clock import MS, S
from fieldtwin.errors import ConfigError
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


def test_constant() -> None:
    assert Constant(3.2).value_at(10**9) == 3.2
    assert Constant(3).value_at(0) == 3.0
    assert Constant(3.2).next_change(0) is None


def test_step() -> None:
    signal = Step(4.0, 20.0, at_us=10 * S)
    assert signal.value_at(10 * S - 1) == 4.0
    assert signal.value_at(10 * S) == 20.0
    assert signal.next_change(0) == 10 * S
    assert signal.next_change(10 * S) is None
    assert Step(1.0, 1.0, 5).next_change(0) is None


def test_ramp_holds_outside() -> None:
    signal = Ramp(4.0, 20.0, t0_us=10 * S, duration_us=30 * S)
    assert signal.value_at(0) == 4.0
    assert signal.value_at(10 * S) == 4.0
    assert signal.value_at(25 * S) == pytest.approx(12.0)
    assert signal.value_at(40 * S) == 20.0
    assert signal.value_at(99 * S) == 20.0
    assert signal.next_change(0) == 10 * S  # the ramp starts
    assert signal.next_change(10 * S) == 40 * S  # the ramp ends
    assert signal.next_change(40 * S) is None


def test_ramp_of_zero_duration_is_a_step() -> None:
    signal = Ramp(0.0, 1.0, t0_us=5, duration_us=0)
    assert (signal.value_at(4), signal.value_at(5)) == (0.0, 1.0)
    assert signal.next_change(0) == 5
    assert signal.next_change(5) is None


def test_sine() -> None:
    signal = Sine(offset=5.0, amplitude=2.0, period_us=60 * S)
    assert signal.value_at(0) == pytest.approx(5.0)
    assert signal.value_at(15 * S) == pytest.approx(7.0)
    assert signal.value_at(45 * S) == pytest.approx(3.0)
    assert signal.value_at(10**6 * 60 * S + 15 * S) == pytest.approx(7.0)  # no drift
    assert Sine(0.0, 1.0, 4, phase_deg=90).value_at(0) == pytest.approx(1.0)
    assert signal.next_change(0) is None


def test_square() -> None:
    signal = Square(low=0.0, high=10.0, period_us=1000, duty=0.3)
    assert [signal.value_at(t) for t in (0, 299, 300, 999, 1000)] == [10, 10, 0, 0, 10]
    assert signal.next_change(0) == 300
    assert signal.next_change(300) == 1000
    assert signal.next_change(1299) == 1300
    assert Square(0.0, 1.0, 1000, duty=1.0).next_change(0) is None


def test_piecewise_linear_interpolates_and_holds() -> None:
    signal = PiecewiseLinear([(1 * S, 0.0), (3 * S, 10.0), (3 * S, 2.0), (5 * S, 2.0)])
    assert signal.value_at(0) == 0.0
    assert signal.value_at(2 * S) == pytest.approx(5.0)
    assert signal.value_at(3 * S - 1) == pytest.approx(10.0, abs=1e-4)
    assert signal.value_at(3 * S) == 2.0  # a jump: the second value holds from then on
    assert signal.value_at(9 * S) == 2.0
    assert signal.next_change(0) == 1 * S
    assert signal.next_change(1 * S) == 3 * S
    assert signal.next_change(3 * S) == 5 * S
    assert signal.next_change(5 * S) is None


@pytest.mark.parametrize(
    ("points", "message"),
    [
        ([], "at least one"),
        ([(2, 1.0), (1, 1.0)], "goes back"),
        ([(1, 1.0), (1, 2.0), (1, 3.0)], "three points"),
        ([(0.5, 1.0)], "whole microseconds"),
        ([(0, math.nan)], "finite number"),
    ],
)
def test_piecewise_linear_rejects(points: list[tuple[int, float]], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        PiecewiseLinear(points)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Constant(math.inf), "value must be a finite number"),
        (lambda: Constant(True), "value must be a finite number"),
        (lambda: Sine(0, 1, 0), "period must be a whole number of us > 0"),
        (lambda: Square(0, 1, 10, duty=-0.1), "duty must be within 0..1"),
        (lambda: Ramp(0, 1, 0, -1), "duration must be >= 0"),
        (lambda: Noise(Constant(0), -1, 1), "sigma must be >= 0"),
        (lambda: Noise(Constant(0), 1, 1, 0), "sample period"),
        (lambda: Sum([]), "at least one"),
    ],
)
def test_rejected_arguments(build: object, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        build()  # type: ignore[operator]


def test_noise_is_seeded_and_held_per_sample() -> None:
    signal = Noise(Constant(12.0), sigma=0.5, seed=1, sample_period_us=10 * MS)
    assert signal.value_at(0) == signal.value_at(10 * MS - 1)
    assert signal.value_at(10 * MS) != signal.value_at(0)
    assert signal.next_change(0) == 10 * MS
    again = Noise(Constant(12.0), sigma=0.5, seed=1, sample_period_us=10 * MS)
    assert again.value_at(5 * S) == signal.value_at(5 * S)
    other = Noise(Constant(12.0), sigma=0.5, seed=2, sample_period_us=10 * MS)
    assert other.value_at(5 * S) != signal.value_at(5 * S)


def test_noise_statistics() -> None:
    signal = Noise(Constant(5.0), sigma=0.01, seed=7, sample_period_us=1)
    values = [signal.value_at(t) for t in range(20_000)]
    assert statistics.fmean(values) == pytest.approx(5.0, abs=0.0005)
    assert statistics.stdev(values) == pytest.approx(0.01, rel=0.05)


def test_noise_follows_its_base_breakpoints() -> None:
    signal = Noise(Step(0.0, 1.0, 1500), sigma=0.1, seed=1, sample_period_us=1000)
    assert signal.next_change(1000) == 1500
    assert signal.next_change(1500) == 2000
    assert Noise(Step(0.0, 1.0, 1500), 0.0, 1).next_change(0) == 1500


@given(st.integers(-(2**64), 2**64), st.lists(st.integers(0, 10**9), min_size=1, max_size=20))
def test_noise_query_order_independent(seed: int, times: list[int]) -> None:
    first = Noise(Sine(1.0, 1.0, 10**6), sigma=1.0, seed=seed, sample_period_us=100)
    second = Noise(Sine(1.0, 1.0, 10**6), sigma=1.0, seed=seed, sample_period_us=100)
    forward = [first.value_at(t) for t in times]
    assert [second.value_at(t) for t in reversed(times)] == forward[::-1]
    assert all(math.isfinite(v) for v in forward)


def test_sum_adds_values_and_breakpoints() -> None:
    signal = Sum([Constant(1.0), Step(0.0, 2.0, 100), Square(0.0, 1.0, 1000, duty=0.5)])
    assert signal.value_at(0) == 2.0
    assert signal.value_at(100) == 4.0
    assert signal.value_at(600) == 3.0
    assert signal.next_change(0) == 100
    assert signal.next_change(100) == 500


# --- properties: piecewise-constant signals are constant up to their next change ----

step_like = st.one_of(
    st.builds(Step, st.floats(-1e6, 1e6), st.floats(-1e6, 1e6), st.integers(0, 10**7)),
    st.builds(
        Square,
        st.floats(-1e6, 1e6),
        st.floats(-1e6, 1e6),
        st.integers(1, 10**6),
        st.floats(0, 1),
    ),
    st.builds(Constant, st.floats(-1e6, 1e6)),
)


@given(step_like, st.integers(0, 10**8), st.integers(0, 2**32))
def test_piecewise_constant_until_next_change(signal: AnalogSignal, t: int, pick: int) -> None:
    value = signal.value_at(t)
    nxt = signal.next_change(t)
    if nxt is None:
        assert signal.value_at(t + 10**9) == value
        return
    assert nxt > t
    assert signal.value_at(nxt - 1) == value
    assert signal.value_at(t + pick % (nxt - t)) == value
    assert signal.value_at(nxt) != value


@given(
    st.lists(st.tuples(st.integers(0, 10**7), st.floats(-1e3, 1e3)), min_size=1, max_size=10).map(
        lambda pts: sorted(dict(pts).items())
    ),
    st.integers(-10, 2 * 10**7),
)
def test_piecewise_linear_stays_within_its_points(points: list[tuple[int, float]], t: int) -> None:
    signal = PiecewiseLinear(points)
    values = [v for _, v in points]
    assert min(values) - 1e-9 <= signal.value_at(t) <= max(values) + 1e-9
    nxt = signal.next_change(t)
    assert nxt is None or (nxt > t and nxt in dict(points))
