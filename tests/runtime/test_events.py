"""The event bus: filters, bounded queues that drop the oldest, no cost when unobserved."""

from __future__ import annotations

import pytest

from fieldtwin.runtime.events import EventBus


def test_an_unobserved_bus_builds_nothing() -> None:
    bus = EventBus()
    assert not bus.active
    bus.publish(1, "modbus", "x", {})
    assert bus.published == 0


def test_filters_by_kind_and_device() -> None:
    bus = EventBus()
    sub = bus.subscribe(kinds={"modbus"}, devices={"a"})
    bus.publish(1, "modbus", "a", {"n": 1})
    bus.publish(2, "modbus", "b", {"n": 2})
    bus.publish(3, "serial", "a", {"n": 3})
    assert [e.data["n"] for e in sub.take()] == [1]
    assert sub.take() == []


def test_a_slow_subscriber_loses_its_oldest_events_and_counts_them() -> None:
    bus = EventBus()
    slow = bus.subscribe(maxlen=3)
    for i in range(10):
        bus.publish(i, "k", "d", {"i": i})
    assert [e.t_us for e in slow.take()] == [7, 8, 9]
    assert slow.dropped == 7


def test_subscriptions_are_bounded_and_leave_when_closed() -> None:
    bus = EventBus(max_subscribers=2)
    a = bus.subscribe()
    bus.subscribe()
    with pytest.raises(OverflowError):
        bus.subscribe()
    a.close()
    bus.subscribe()
    assert bus.active


def test_event_as_dict_is_in_seconds() -> None:
    bus = EventBus()
    sub = bus.subscribe()
    bus.publish(1_500_000, "clock", "plant", {"paused": True})
    assert sub.take()[0].as_dict() == {
        "t_s": 1.5,
        "kind": "clock",
        "device": "plant",
        "paused": True,
    }
