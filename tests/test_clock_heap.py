"""SimClock's heap: cancelled entries never bloat it, and compaction keeps the order."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.clock import COMPACT_MIN, Handle, SimClock


def test_an_event_rescheduled_on_every_edge_keeps_the_heap_small() -> None:
    # the DEM's oscillation check: cancelled and scheduled again at every edge
    clock = SimClock()
    fired: list[int] = []
    handle = clock.schedule(10**9, fired.append)
    for k in range(100_000):
        handle.cancel()
        handle = clock.schedule(10**9 + k, fired.append)
    assert clock.pending <= 2 * COMPACT_MIN + 1
    clock.advance(2 * 10**9)
    assert fired == [10**9 + 99_999]


def test_cancel_after_firing_and_twice_is_harmless() -> None:
    clock = SimClock()
    seen: list[int] = []
    handle = clock.schedule(5, seen.append)
    clock.advance(10)
    handle.cancel()
    handle.cancel()
    assert not handle.active and seen == [5] and clock.next_deadline() is None


ops = st.lists(
    st.one_of(
        st.tuples(st.just("at"), st.integers(0, 50), st.integers(-1, 1)),
        st.tuples(st.just("cancel"), st.integers(0, 10_000), st.just(0)),
        st.tuples(st.just("run"), st.integers(0, 20), st.just(0)),
    ),
    max_size=400,
)


@given(ops)
def test_same_order_as_a_sorted_reference(script: list[tuple[str, int, int]]) -> None:
    """Whatever is scheduled and cancelled, events run in (time, priority, insertion)
    order, each once, as a plain sorted list of live events would run them."""
    clock = SimClock()
    handles: list[Handle] = []
    live: dict[int, tuple[int, int, int]] = {}  # id -> (time, priority, seq)
    seen: list[int] = []
    expected: list[int] = []
    for op, a, b in script:
        if op == "at":
            n = len(handles)
            at = clock.now + a
            handles.append(clock.schedule(at, lambda t, n=n: seen.append(n), priority=b))
            live[n] = (at, b, n)
        elif op == "cancel" and handles:
            n = a % len(handles)
            handles[n].cancel()
            live.pop(n, None)
        elif op == "run":
            until = clock.now + a
            due = sorted((v, n) for n, v in live.items() if v[0] <= until)
            expected += [n for _, n in due]
            for _, n in due:
                del live[n]
            clock.run_until(until)
            assert seen == expected
    assert all(h.active == (n in live) for n, h in enumerate(handles))


def test_run_one_runs_a_single_event_of_an_instant_and_skips_cancelled_ones() -> None:
    from fieldtwin.clock import SimClock

    clock = SimClock()
    seen: list[str] = []
    gone = clock.schedule(5, lambda t: seen.append("cancelled"))
    clock.schedule(5, lambda t: seen.append("a"))
    clock.schedule(5, lambda t: seen.append("b"))
    gone.cancel()
    assert clock.run_one() and seen == ["a"] and clock.now == 5
    assert clock.run_one() and seen == ["a", "b"] and clock.fired == 2
    assert not clock.run_one()
