"""The plant's event bus: what windows onto the running plant observe (DESIGN rule 13).

Publishers (the Modbus servers, the SCM endpoints, the PLC cycle) call
``bus.publish(...)`` from the simulation's thread, at the simulated instant the
thing happened.  Subscribers (the control API's event stream, a trace file, the
console's ``trace`` command) each get a bounded queue: when a subscriber does
not keep up, its oldest events are dropped and counted, so an observer never
slows the plant nor grows its memory (DESIGN rule 14).  ``bus.active`` tells a
publisher whether anybody listens, so that an unobserved plant pays nothing.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass

DEFAULT_QUEUE = 10_000  # events a subscriber may have unread before the oldest are dropped
MAX_SUBSCRIBERS = 64  # subscriptions one bus accepts at once


@dataclass(frozen=True, slots=True)
class Event:
    """One thing that happened: when (simulated us), what kind, on which device, its fields."""

    t_us: int
    kind: str  # "modbus", "serial", "object", "led", "dem", "register", "clock", ...
    device: str  # the device's address as the Device face writes it ("5", "tcp://...:5020 1")
    data: Mapping[str, object]

    def as_dict(self) -> dict[str, object]:
        return {"t_s": self.t_us / 1e6, "kind": self.kind, "device": self.device, **self.data}


class Subscription:
    """A bounded queue of the events one observer asked for."""

    def __init__(
        self,
        bus: EventBus,
        kinds: Collection[str] | None,
        devices: Collection[str] | None,
        maxlen: int,
        notify: Callable[[], None] | None,
    ) -> None:
        self._bus = bus
        self.kinds = frozenset(kinds) if kinds else None
        self.devices = frozenset(devices) if devices else None
        self._queue: deque[Event] = deque(maxlen=maxlen)
        self._lock = threading.Lock()
        self._notify = notify
        self.dropped = 0  # events lost because this subscriber did not keep up
        self.closed = False

    def wants(self, event: Event) -> bool:
        return (self.kinds is None or event.kind in self.kinds) and (
            self.devices is None or event.device in self.devices
        )

    def _put(self, event: Event) -> None:
        with self._lock:
            if len(self._queue) == self._queue.maxlen:
                self.dropped += 1
            self._queue.append(event)
        if self._notify is not None:
            self._notify()

    def take(self, limit: int = 1000) -> list[Event]:
        """Up to ``limit`` events, oldest first (never blocks)."""
        with self._lock:
            count = min(limit, len(self._queue))
            return [self._queue.popleft() for _ in range(count)]

    def __len__(self) -> int:
        return len(self._queue)

    def close(self) -> None:
        self.closed = True
        self._bus._remove(self)


class EventBus:
    """Fan-out of events to bounded subscriptions."""

    def __init__(self, max_subscribers: int = MAX_SUBSCRIBERS) -> None:
        self._subs: tuple[Subscription, ...] = ()
        self._lock = threading.Lock()
        self.max_subscribers = max_subscribers
        self.published = 0

    @property
    def active(self) -> bool:
        """True while somebody listens: publishers may skip building events otherwise."""
        return bool(self._subs)

    def publish(self, t_us: int, kind: str, device: str, data: Mapping[str, object]) -> None:
        subs = self._subs
        if not subs:
            return
        event = Event(t_us, kind, device, data)
        self.published += 1
        for sub in subs:
            if sub.wants(event):
                sub._put(event)

    def subscribe(
        self,
        kinds: Collection[str] | None = None,
        devices: Collection[str] | None = None,
        *,
        maxlen: int = DEFAULT_QUEUE,
        notify: Callable[[], None] | None = None,
    ) -> Subscription:
        """A new subscription; ``notify`` is called (from the simulation's thread) on each event."""
        if maxlen < 1:
            raise ValueError("a subscription holds at least one event")
        sub = Subscription(self, kinds, devices, maxlen, notify)
        with self._lock:
            if len(self._subs) >= self.max_subscribers:
                raise OverflowError(f"at most {self.max_subscribers} subscribers at once")
            self._subs = (*self._subs, sub)
        return sub

    def _remove(self, sub: Subscription) -> None:
        with self._lock:
            self._subs = tuple(s for s in self._subs if s is not sub)


__all__ = ["DEFAULT_QUEUE", "MAX_SUBSCRIBERS", "Event", "EventBus", "Subscription"]
