"""Discrete signals: values, next edges, determinism (fieldtwin.signals.discrete)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS, S
from fieldtwin.errors import ConfigError
from fieldtwin.signals import (
    DiscreteConstant,
    DiscreteSignal,
    Edges,
    PulseTrain,
    RandomEdges,
)

# --- examples ------------------------------------------------------------------------


def test_constant_never_changes() -> None:
    signal = DiscreteConstant(True)
    assert signal.value_at(0) is True
    assert signal.next_change(0) is None


def test_pulse_train_high_first() -> None:
    signal = PulseTrain(period_us=30 * S, duty=0.01, start_us=5 * S)
    assert signal.value_at(0) is False
    assert signal.next_change(0) == 5 * S
    assert signal.value_at(5 * S) is True
    assert signal.next_change(5 * S) == 5 * S + 300 * MS  # 1 % of 30 s
    assert signal.value_at(5 * S + 300 * MS) is False
    assert signal.next_change(5 * S + 300 * MS) == 35 * S
    assert signal.value_at(35 * S) is True


def test_pulse_train_low_first() -> None:
    signal = PulseTrain(period_us=1000, duty=0.25, high_first=False)
    assert [signal.value_at(t) for t in (0, 749, 750, 999, 1000, 1750)] == [
        False,
        False,
        True,
        True,
        False,
        True,
    ]
    assert signal.next_change(0) == 750
    assert signal.next_change(750) == 1000
    assert signal.next_change(1000) == 1750


@pytest.mark.parametrize(("duty", "value"), [(0.0, False), (1.0, True)])
def test_pulse_train_degenerate_duty(duty: float, value: bool) -> None:
    signal = PulseTrain(period_us=1000, duty=duty, start_us=10)
    assert signal.value_at(5000) is value
    assert signal.next_change(5000) is None
    assert signal.next_change(0) == (10 if value else None)


def test_edges_toggle() -> None:
    signal = Edges(False, [1 * S, 1500 * MS])
    assert [signal.value_at(t) for t in (0, 1 * S - 1, 1 * S, 1500 * MS, 9 * S)] == [
        False,
        False,
        True,
        False,
        False,
    ]
    assert signal.next_change(0) == 1 * S
    assert signal.next_change(1 * S) == 1500 * MS
    assert signal.next_change(1500 * MS) is None


def test_edges_from_list_skips_repeats() -> None:
    signal = Edges.from_list([(0, False), (100, True), (200, True), (300, False)])
    assert signal.times_us == (100, 300)
    assert signal.value_at(250) is True
    assert Edges.from_list([(0, True)]).value_at(0) is True
    assert Edges.from_list([(0, True)], initial=True).times_us == ()


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Edges(False, [5, 5]), "edge times must increase"),
        (lambda: Edges(False, [5, 3]), "edge times must increase"),
        (lambda: Edges(False, [1.5]), "whole microseconds"),  # type: ignore[list-item]
        (lambda: Edges.from_list([(5, True), (5, False)]), "not after the previous"),
        (lambda: PulseTrain(0), "period must be a whole number of us > 0"),
        (lambda: PulseTrain(100, duty=1.5), "duty must be within 0..1"),
        (lambda: RandomEdges(1, 10, min_interval_us=20), "allowed mean >= min"),
        (lambda: RandomEdges(1, 10, min_interval_us=0), "min interval"),
    ],
)
def test_rejected_arguments(build: object, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        build()  # type: ignore[operator]


def test_random_edges_respect_min_interval_and_mean() -> None:
    signal = RandomEdges(seed=3, mean_interval_us=2 * S, min_interval_us=1 * MS)
    edges: list[int] = []
    t = 0
    while len(edges) < 2000:
        nxt = signal.next_change(t)
        assert nxt is not None
        edges.append(nxt)
        t = nxt
    intervals = [b - a for a, b in zip([0, *edges], edges, strict=False)]
    assert min(intervals) >= 1 * MS
    mean = sum(intervals) / len(intervals)
    assert 1.8 * S < mean < 2.2 * S  # 2000 exponential draws: within 10 %


def test_random_edges_query_order_independent() -> None:
    times = [0, 7 * S, 3 * S, 100 * S, 55 * S, 1 * S, 99 * S]
    forward = RandomEdges(seed=9, mean_interval_us=2 * S)
    answers = {t: (forward.value_at(t), forward.next_change(t)) for t in sorted(times)}
    backward = RandomEdges(seed=9, mean_interval_us=2 * S)
    for t in reversed(times):
        assert (backward.value_at(t), backward.next_change(t)) == answers[t]


def test_random_edges_seed_matters() -> None:
    a = RandomEdges(seed=1, mean_interval_us=S)
    b = RandomEdges(seed=2, mean_interval_us=S)
    assert [a.next_change(k * S) for k in range(10)] != [b.next_change(k * S) for k in range(10)]


def test_random_edges_before_zero() -> None:
    signal = RandomEdges(seed=1, mean_interval_us=S, initial=True)
    assert signal.value_at(-5) is True
    first = signal.next_change(-5)
    assert first is not None and first >= 1 * MS


# --- properties of every discrete signal -------------------------------------------

times = st.integers(0, 10**8)


def discrete_signals() -> st.SearchStrategy[DiscreteSignal]:
    pulse = st.builds(
        PulseTrain,
        period_us=st.integers(1, 10**6),
        duty=st.floats(0, 1),
        start_us=st.integers(0, 10**7),
        high_first=st.booleans(),
    )
    edges = st.builds(
        Edges,
        initial=st.booleans(),
        times_us=st.lists(st.integers(0, 10**8), max_size=20, unique=True).map(sorted),
    )
    random = st.builds(
        RandomEdges,
        seed=st.integers(-(2**70), 2**70),
        mean_interval_us=st.integers(1000, 10**6),
        min_interval_us=st.integers(1, 1000),
        initial=st.booleans(),
    )
    constant = st.builds(DiscreteConstant, st.booleans())
    return st.one_of(pulse, edges, random, constant)


@settings(max_examples=300)
@given(discrete_signals(), times, st.integers(0, 2**32))
def test_next_change_is_the_next_edge(signal: DiscreteSignal, t: int, pick: int) -> None:
    value = signal.value_at(t)
    assert isinstance(value, bool)
    nxt = signal.next_change(t)
    if nxt is None:
        for later in (t + 1, t + 12_345, t + 10**9):
            assert signal.value_at(later) is value
        return
    assert nxt > t
    assert signal.value_at(nxt) is not value
    assert signal.value_at(nxt - 1) is value
    inside = t + pick % (nxt - t)
    assert signal.value_at(inside) is value
    assert signal.next_change(inside) == nxt


@given(discrete_signals(), st.lists(times, min_size=1, max_size=10))
def test_value_at_is_deterministic(signal: DiscreteSignal, queries: list[int]) -> None:
    first = [signal.value_at(t) for t in queries]
    assert [signal.value_at(t) for t in reversed(queries)] == first[::-1]
