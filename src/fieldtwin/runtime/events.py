"""The plant's event bus: what windows onto the running plant observe (DESIGN rule 13).

Publishers (the Modbus servers' wiretaps, the SCM endpoints, the PLC cycle) call
``bus.publish(...)`` or ``bus.post(...)`` from the simulation's thread, at the
simulated instant the thing happened.  Subscribers (the control API's event stream, a
trace file, a pcap, the console's ``trace`` command) each get a bounded queue: when a
subscriber does not keep up, its oldest events are dropped and counted, so an observer
never slows the plant nor grows its memory (DESIGN rule 14).  ``bus.active`` tells a
publisher whether anybody listens, so that an unobserved plant pays nothing.

Off the hot path: once ``start()`` was called (``fieldtwin run``), the simulation's
thread only appends a raw record of plain data (``OP_*`` of fieldtwin.runtime.obsrecords:
the bytes of a frame, the time, the small tuple of a device's state) to one bounded
buffer (``FEED`` records; when full, a record is lost and counted as dropped for every
subscriber).  The observers' thread takes the buffer every ``BATCH_S`` and ships it to
the observers' own process (``start(ObserversProcess.start)``, runtime.obslink), which
frames, decodes, writes the trace and pcap and filters each ``/events`` subscriber
(``subscribe(remote=True)``); subscribers in this process (the console's ``trace``;
all when that process could not start) are served on the observers' thread, in order.
Without ``start()`` (tests, the console) a record is handled at once, as before.

``listen(kinds, callback)`` is the one exception: the callback runs on the simulation's
thread at the instant of publication (a recording's SCM and DEM records, which must
stay in order with the bytes it logs; it does no more than append them to its own
writer's queue, fieldtwin.runtime.record).
"""

from __future__ import annotations

import itertools
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Collection, Mapping
from typing import Any

from fieldtwin.runtime.obsrecords import (
    MAX_STREAMS,
    OP_EVENT,
    OP_FORGET,
    OP_STREAM,
    OP_TAP,
    STREAM_OPS,
    Event,
    Link,
    Tapped,
)

DEFAULT_QUEUE = 10_000  # events a subscriber may have unread before the oldest are dropped
MAX_SUBSCRIBERS = 64  # subscriptions one bus accepts at once
FEED = 100_000  # raw records the simulation's thread may have handed the observers unread
BATCH_S = 0.005  # the observers' thread takes the buffer this often (while it holds any)
CHUNK = 64  # records handled between two yields of the observers' thread
YIELD_S = 0.0001  # a yield: long enough for the simulation's thread to take the interpreter
SWITCH_S = 0.0005  # the interpreter's switch interval once started (Python's default: 5 ms)
STOP_WAIT_S = 10.0  # close() waits this long for the observers' thread
DECODED_KINDS = frozenset(("modbus", "register"))  # what a wiretap decodes the frames for
Listener = Callable[[int, str, str, Mapping[str, object]], None]


class Subscription:
    """A bounded queue of the events one observer asked for."""

    def __init__(
        self,
        bus: EventBus,
        kinds: Collection[str] | None,
        devices: Collection[str] | None,
        maxlen: int,
        notify: Callable[[], None] | None,
        raw: bool = False,
    ) -> None:
        self._bus = bus
        self.raw = raw  # it reads a frame's bytes and where they went, never its fields
        self.kinds = frozenset(kinds) if kinds else None
        self.devices = frozenset(devices) if devices else None
        self._queue: deque[Event] = deque(maxlen=maxlen)
        self._lock = threading.Lock()
        self._notify = notify
        self._fresh = False  # events came since the last wake-up (the observers' thread)
        self.dropped = 0  # events lost because this subscriber did not keep up
        self.closed = False

    def wants(self, event: Event) -> bool:
        return (self.kinds is None or event.kind in self.kinds) and (
            self.devices is None or event.device in self.devices
        )

    def _put(self, event: Event, notify: bool = True) -> None:
        with self._lock:
            if len(self._queue) == self._queue.maxlen:
                self.dropped += 1
            self._queue.append(event)
        if not notify:
            self._fresh = True
        elif self._notify is not None:
            self._notify()

    def _lost(self, count: int) -> None:
        with self._lock:
            self.dropped += count
        self._fresh = True

    def _wake(self) -> None:
        if self._fresh:
            self._fresh = False
            if self._notify is not None:
                self._notify()

    def take(self, limit: int = 1000) -> list[Event]:
        """Up to ``limit`` events, oldest first (never blocks)."""
        with self._lock:
            count = min(limit, len(self._queue))
            return [self._queue.popleft() for _ in range(count)]

    def texts(self, limit: int = 1000) -> list[str]:
        """``take(limit)`` as each event's JSON text (what ``/events`` sends)."""
        return [event.json() for event in self.take(limit)]

    def __len__(self) -> int:
        return len(self._queue)

    def close(self) -> None:
        self.closed = True
        self._bus._remove(self)


class EventBus:
    """Fan-out of events to bounded subscriptions (see the module docstring)."""

    def __init__(self, max_subscribers: int = MAX_SUBSCRIBERS, feed: int = FEED) -> None:
        self._subs: tuple[Subscription, ...] = ()
        self._listeners: tuple[tuple[frozenset[str], Listener], ...] = ()
        self._lock = threading.Lock()
        self.max_subscribers = max_subscribers
        self.published = 0
        self.feed_size = feed
        self._feed: deque[tuple[Any, ...]] | None = None  # None: records handled at once
        self._lost = 0  # records the full buffer refused (the observers' thread adds them up)
        self._round = threading.Lock()  # one round of the observers' work at a time
        self._wake = threading.Event()
        self._thread: threading.Thread | None = None
        self._closing = False
        self.errors = 0  # records whose handling raised (a bug: said once on stderr)
        self._ids = itertools.count(1)  # numbers of wiretaps, streams, subscriptions
        self._streams: dict[int, Any] = {}  # number -> wiretap.Stream (OP_IN ... OP_REJECTED)
        self._link: Link | None = None  # the observers' process, when it runs
        self._taps: set[int] = set()  # wiretaps the process was told of
        self.remote = 0  # subscriptions and file writers the process holds
        # a subscription here wants the wire's frames decoded (``modbus`` fields, the
        # ``register`` events): False while only ``raw`` ones (a pcap) take them
        self.decoding = False
        # the observers' process handles whole batches at once (never started): its
        # subscribers are woken once a batch (``wake``), not once an event
        self.deferred = False

    @property
    def active(self) -> bool:
        """True while somebody listens: publishers may skip building events otherwise."""
        return bool(self._subs) or bool(self._listeners) or self.remote > 0

    @property
    def watched(self) -> bool:
        """True while a subscription exists (a wiretap's frames go only to those)."""
        return bool(self._subs) or self.remote > 0

    @property
    def link(self) -> Link | None:
        """The observers' process, while it runs."""
        link = self._link
        return link if link is not None and link.alive else None

    # --- the simulation's side ---------------------------------------------------------

    def post(self, record: tuple[Any, ...]) -> None:
        """Hand the observers one raw record (``OP_*``, plain data), handled on the
        observers' side (at once when the bus was not started)."""
        feed = self._feed
        if feed is None:
            self.handle(record)
            return
        if len(feed) >= self.feed_size:
            self._lost += 1
            return
        feed.append(record)
        if len(feed) == 1:
            self._wake.set()

    def control(self, record: tuple[Any, ...]) -> None:
        """A control record: in order with the data, never refused."""
        feed = self._feed
        if feed is None:
            self.handle(record)
        else:
            feed.append(record)
            self._wake.set()

    def publish(self, t_us: int, kind: str, device: str, data: Mapping[str, object]) -> None:
        for kinds, callback in self._listeners:
            if kind in kinds:
                callback(t_us, kind, device, data)
        if self._subs or self.remote:
            self.post((OP_EVENT, t_us, kind, device, data))

    def attach(self, stream: Tapped, number: int | None = None) -> int:
        """Number ``stream`` (a wiretap's) for the records that name it; the observers'
        process is told of it (and of its wiretap, the first time)."""
        if number is None:
            number = next(self._ids)
        streams = self._streams
        if len(streams) >= MAX_STREAMS:
            streams.pop(next(iter(streams)))
        streams[number] = stream
        if self._link is not None and self._feed is not None:
            tap = stream.tap
            if tap.tid not in self._taps:
                self._taps.add(tap.tid)
                self.control((OP_TAP, tap.tid, tap.spec()))
            self.control((OP_STREAM, number, tap.tid, stream.conn))
        return number

    def new_id(self) -> int:
        return next(self._ids)

    def listen(self, kinds: Collection[str], callback: Listener) -> Callable[[], None]:
        """Call ``callback(t_us, kind, device, data)`` on the publishing (simulation's)
        thread for every event of ``kinds``; returns what stops it."""
        entry = (frozenset(kinds), callback)
        with self._lock:
            self._listeners = (*self._listeners, entry)

        def stop() -> None:
            with self._lock:
                self._listeners = tuple(e for e in self._listeners if e is not entry)

        return stop

    # --- the observers' side -----------------------------------------------------------

    def handle(self, record: tuple[Any, ...]) -> None:
        """One raw record, in this process."""
        op = record[0]
        if op == OP_EVENT:
            self.deliver(*record[1:])
        elif op in STREAM_OPS:
            stream = self._streams.get(record[1])
            if stream is not None:
                getattr(stream, STREAM_OPS[op])(*record[2:])
        elif op == OP_FORGET:
            self._streams.pop(record[1], None)

    def deliver(
        self,
        t_us: int,
        kind: str,
        device: str,
        data: Mapping[str, object],
        body: str | None = None,
    ) -> None:
        """One event to every subscription that wants it (the observers' side);
        ``body``: its JSON but the time, when known (``Event.body``)."""
        subs = self._subs
        if not subs:
            return
        event = Event(t_us, kind, device, data, body)
        self.published += 1
        inline = self._feed is None and not self.deferred
        for sub in subs:
            kinds, devices = sub.kinds, sub.devices  # ``sub.wants(event)``, inline
            if (kinds is None or kind in kinds) and (devices is None or device in devices):
                sub._put(event, inline)

    def process(self) -> int:
        """Handle every record waiting, in order, then wake the subscribers that got
        events; returns how many records were handled."""
        feed = self._feed
        if feed is None:
            return 0
        handled = 0
        with self._round:
            while feed:
                batch = [feed.popleft() for _ in range(len(feed))]
                lost, self._lost = self._lost, 0
                link = self._link
                if link is not None:
                    link.ship(batch, lost)  # the observers' process does the work
                if self._subs:
                    self._here(batch, lost)
                else:  # nobody here: only what the stream table needs
                    for record in batch:
                        if record[0] == OP_FORGET:
                            self._streams.pop(record[1], None)
                handled += len(batch)
            self._wake_subscribers()
        return handled

    def _here(self, batch: list[tuple[Any, ...]], lost: int) -> None:
        """The work of ``batch`` on this thread, for the subscribers in this process."""
        self._wake_subscribers(lost)
        for start in range(0, len(batch), CHUNK):
            if start:
                time.sleep(YIELD_S)  # the simulation's thread may want the interpreter
            for record in batch[start : start + CHUNK]:
                try:
                    self.handle(record)
                except Exception as exc:  # a decoder's bug: told, the plant runs on
                    self._failed(exc)
            self._wake_subscribers()  # a file writer drains its queue chunk by chunk

    def wake(self) -> None:
        """Wake the subscribers that got events since the last wake (``deferred``)."""
        self._wake_subscribers()

    def _wake_subscribers(self, lost: int = 0) -> None:
        for sub in self._subs:
            if lost:
                sub._lost(lost)
            sub._wake()

    def _failed(self, exc: Exception) -> None:
        self.errors += 1
        if self.errors == 1:
            print(f"fieldtwin: an observer failed ({exc!r}); said once", file=sys.stderr)

    def start(self, process: Callable[[EventBus], Link | None] | None = None) -> None:
        """From now on the simulation's thread only appends records; a thread of the
        observers' does the work, or ships it to the process ``process`` starts
        (fieldtwin.runtime.obslink's ``ObserversProcess.start``; idempotent)."""
        if self._thread is not None:
            return
        if process is not None:
            self._link = process(self)
        # a thread waiting for the interpreter (the simulation's, back from a socket call)
        # gets it after this long at most, not after Python's 5 ms (the web server's
        # thread runs Python too): the observers' work never holds the plant long
        sys.setswitchinterval(min(sys.getswitchinterval(), SWITCH_S))
        self._feed = deque()
        self._thread = threading.Thread(target=self._run, name="fieldtwin-observers", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._closing:
            self._wake.wait(1.0)
            if self._closing:
                break
            self._wake.clear()
            time.sleep(BATCH_S)  # a batch gathers: one round per batch, not per record
            self.process()
        self.process()

    def close(self) -> None:
        """Handle what is left and stop the observers' thread (idempotent)."""
        thread = self._thread
        if thread is None:
            return
        self._closing = True
        self._wake.set()
        if thread is not threading.current_thread():
            thread.join(STOP_WAIT_S)
        self.process()
        self._feed = None  # what is published from now on is handled at once
        link, self._link = self._link, None
        if link is not None:
            link.close()  # the process writes what it holds, closes its files, ends

    # --- subscriptions -----------------------------------------------------------------

    def subscribe(
        self,
        kinds: Collection[str] | None = None,
        devices: Collection[str] | None = None,
        *,
        maxlen: int = DEFAULT_QUEUE,
        notify: Callable[[], None] | None = None,
        remote: bool = False,
        raw: bool = False,
    ) -> Any:
        """A new subscription; ``notify`` is called when events came: on each event when
        the bus was not started, else once per batch from the observers' thread.
        ``remote``: filtered and encoded in the observers' process when it runs (its
        ``texts()`` are what it sent; fieldtwin.runtime.obslink), here otherwise.
        ``raw``: it reads only the bytes of the ``modbus`` events and where they went
        (``hex``, ``dir``, ``conn``, ...): while no other subscription wants them, the
        wiretaps skip decoding the frames' fields (a pcap's case)."""
        if maxlen < 1:
            raise ValueError("a subscription holds at least one event")
        with self._lock:
            if len(self._subs) + self.remote >= self.max_subscribers:
                raise OverflowError(f"at most {self.max_subscribers} subscribers at once")
            link = self.link if remote else None
            if link is not None:
                return link.subscribe(kinds, devices, maxlen, notify)
            sub = Subscription(self, kinds, devices, maxlen, notify, raw)
            self._subs = (*self._subs, sub)
            self._decoding()
        return sub

    def _remove(self, sub: Subscription) -> None:
        with self._lock:
            self._subs = tuple(s for s in self._subs if s is not sub)
            self._decoding()

    def _decoding(self) -> None:
        self.decoding = any(
            not s.raw and (s.kinds is None or not s.kinds.isdisjoint(DECODED_KINDS))
            for s in self._subs
        )


__all__ = [
    "BATCH_S",
    "DEFAULT_QUEUE",
    "FEED",
    "MAX_SUBSCRIBERS",
    "OP_EVENT",
    "Event",
    "EventBus",
    "Subscription",
]
