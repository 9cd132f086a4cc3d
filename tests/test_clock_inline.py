"""SimClock.reserve / schedule_as / run_inline (issue 25): an event put in the heap later
with a reserved sequence number, or run inline, runs where a plain schedule would."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.clock import SimClock

# (delay of the first event, delays of the events it schedules, which of them deferred)
_plan = st.lists(
    st.tuples(
        st.integers(0, 20), st.lists(st.tuples(st.integers(0, 20), st.booleans()), max_size=4)
    ),
    min_size=1,
    max_size=12,
)


def _run(plan: list[tuple[int, list[tuple[int, bool]]]], reserved: bool) -> list[tuple[int, str]]:
    """Each first event schedules its children at once, or (``reserved``, the deferred
    ones) reserves their numbers and puts them in the heap at a later event: a "mover"
    scheduled before the children's instants.  The order must not change."""
    clock = SimClock()
    order: list[tuple[int, str]] = []

    def child(name: str):  # type: ignore[no-untyped-def]
        return lambda now: order.append((now, name))

    def parent(index: int, children: list[tuple[int, bool]]):  # type: ignore[no-untyped-def]
        def fire(now: int) -> None:
            order.append((now, f"p{index}"))
            later = []
            for k, (delay, deferred) in enumerate(children):
                at, cb = now + 1 + delay, child(f"c{index}.{k}")
                if reserved and deferred:
                    later.append((at, clock.reserve(), cb))
                else:
                    clock.schedule(at, cb)
            if later:  # put in the heap from an event at now + 1 (before every child)
                clock.schedule(now + 1, lambda _now: [clock.schedule_as(*e) for e in later], -1)
            elif reserved is False and any(d for _, d in children):
                clock.reserve()  # the mover's own number, in the plain run too
                clock.schedule(now + 1, lambda _now: None, -1)

        return fire

    for index, (delay, children) in enumerate(plan):
        clock.schedule(delay, parent(index, children))
    clock.advance(100)
    return order


@given(_plan)
def test_reserved_numbers_keep_the_order(plan: list[tuple[int, list[tuple[int, bool]]]]) -> None:
    assert _run(plan, True) == _run(plan, False)


def test_run_inline_only_when_nothing_comes_between() -> None:
    clock = SimClock()
    ran: list[tuple[str, int]] = []
    results: list[bool] = []

    def first(now: int) -> None:
        seq = clock.reserve()
        results.append(clock.run_inline(now + 5, seq, lambda t: ran.append(("inline", t))))
        seq = clock.reserve()
        done = clock.run_inline(now + 20, seq, lambda t: ran.append(("late", t)))
        results.append(done)  # an event at 15 comes between
        if not done:
            clock.schedule_as(now + 20, seq, lambda t: ran.append(("late", t)))

    clock.schedule(10, first)
    clock.schedule(25, lambda t: ran.append(("other", t)))
    fired = clock.fired
    clock.run_until(40)
    assert results == [True, False]
    assert ran == [("inline", 15), ("other", 25), ("late", 30)]
    assert clock.fired == fired + 4 and clock.now == 40


def test_run_inline_never_past_the_run_nor_in_run_one() -> None:
    clock = SimClock()
    results: list[bool] = []
    clock.schedule(10, lambda now: results.append(clock.run_inline(now + 5, 0, print)))
    clock.run_until(12)  # the run ends at 12: nobody may see 15 early
    clock.schedule(20, lambda now: results.append(clock.run_inline(now + 1, 0, print)))
    assert clock.run_one()  # a replay stands after each event
    assert results == [False, False]
    assert clock.run_inline(clock.now, 0, print) is False  # outside any run
