"""SimClock: ordering, cancel, bounds (DESIGN rule 2)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.clock import MS, S, SimClock, seconds
from fieldtwin.errors import ConfigError


def test_events_run_in_time_order_and_time_is_their_time() -> None:
    clock = SimClock()
    seen: list[tuple[str, int]] = []
    clock.schedule(30, lambda t: seen.append(("c", t)))
    clock.schedule(10, lambda t: seen.append(("a", t)))
    clock.schedule(20, lambda t: seen.append(("b", t)))
    clock.advance(25)
    assert seen == [("a", 10), ("b", 20)]
    assert clock.now == 25
    clock.advance(5)
    assert seen[-1] == ("c", 30)


def test_same_time_events_run_in_insertion_order_then_priority() -> None:
    clock = SimClock()
    seen: list[str] = []
    for name in "abcde":
        clock.schedule(100, lambda t, n=name: seen.append(n))
    clock.schedule(100, lambda t: seen.append("first"), priority=-1)
    clock.advance(100)
    assert seen == ["first", "a", "b", "c", "d", "e"]


def test_cancel_prevents_the_callback_and_next_deadline_skips_it() -> None:
    clock = SimClock()
    seen: list[int] = []
    handle = clock.schedule(5, seen.append)
    clock.schedule(9, seen.append)
    handle.cancel()
    assert not handle.active
    assert clock.next_deadline() == 9
    clock.advance(10)
    assert seen == [9]


def test_events_scheduled_by_callbacks_within_the_window_run() -> None:
    clock = SimClock()
    seen: list[int] = []

    def tick(t: int) -> None:
        seen.append(t)
        if t < 50:
            clock.call_later(10, tick)

    clock.schedule(0, tick)
    clock.advance(100)
    assert seen == [0, 10, 20, 30, 40, 50]


def test_time_never_goes_back() -> None:
    clock = SimClock()
    clock.advance(10)
    with pytest.raises(ConfigError, match="already"):
        clock.schedule(5, lambda t: None)
    with pytest.raises(ConfigError, match="negative"):
        clock.advance(-1)
    with pytest.raises(ConfigError, match="never goes back"):
        clock.run_until(3)
    with pytest.raises(ConfigError):
        SimClock(-1)


def test_step_runs_the_next_event_only() -> None:
    clock = SimClock()
    seen: list[int] = []
    clock.schedule(7, seen.append)
    clock.schedule(9, seen.append)
    assert clock.step()
    assert seen == [7] and clock.now == 7
    assert clock.step() and clock.step() is False
    assert clock.fired == 2


def test_units() -> None:
    assert seconds(1.5) == 1_500_000 == 1500 * MS == 1.5 * S


@given(st.lists(st.tuples(st.integers(0, 10_000), st.integers(-2, 2)), max_size=60))
def test_any_schedule_runs_sorted_by_time_priority_insertion(
    entries: list[tuple[int, int]],
) -> None:
    clock = SimClock()
    seen: list[tuple[int, int, int]] = []
    for seq, (at, prio) in enumerate(entries):
        clock.schedule(at, lambda t, p=prio, s=seq: seen.append((t, p, s)), priority=prio)
    clock.advance(10_000)
    assert seen == sorted(seen)
    assert len(seen) == len(entries)
