"""The machinery of a replay: a clock that stops between two events, a runner fed by records.

``ReplayRunner`` stands in for the real-time runner of a recorded plant: the
plant, the binder and the commands call it as they would the real one, but it
never waits on the wall and never reads a descriptor.  Its ``_run`` (what
``advance``, ``step``, ``run_until`` and a command's own advance come to)
delivers the recorded inputs whose instant falls inside the run, each between
the very two clock events it arrived between in the recording (the record's
``fired``: how many events had run before it).  What the plant sends on its
virtual transports (fieldtwin.transports.virtual) is collected in ``out``,
in the form of the recording's output records, to be compared with them
(fieldtwin.replay).

``compare``, ``Comparer`` and ``show`` (the first difference between two streams
of output records, shown in context) are fieldtwin.runtime.compare's, named here too.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from functools import partial
from typing import Protocol

from fieldtwin.clock import SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.compare import Comparer, Difference, compare, show
from fieldtwin.runtime.recfile import MAX_SIM_US, RecordingError
from fieldtwin.runtime.record import Keys, Record
from fieldtwin.runtime.runner import CloseCallback, ConnectCallback, DataCallback, Runner
from fieldtwin.runtime.wall import WallClock
from fieldtwin.transports.base import Listener, SendObservable, Transport
from fieldtwin.transports.pty import PeerLine, PtyTransport
from fieldtwin.transports.virtual import VirtualListener


class ReplayClock(SimClock):
    """A SimClock that can stand at an instant with
    events of that instant still due (as the recorded clock stood when bytes came)."""

    def stand_at(self, t_us: int) -> None:
        """Now = ``t_us``; every event before it has run (those at it may wait)."""
        deadline = self.next_deadline()
        if deadline is None or deadline > t_us:
            self.run_until(t_us)
        else:
            assert deadline == t_us and t_us >= self._now
            self._now = t_us


Dispatch = Callable[[Record], None]


class Outputs(Protocol):
    def append(self, record: Record, /) -> None: ...


class Feed:
    """The recorded inputs, one at a time from a stream (never held whole): the next one
    (``head``, or None once they are all delivered, the end record met, or the replay
    refused), the end record when met, and the first reason to refuse the recording."""

    def __init__(self, records: Iterable[tuple[int, Record]], where: str = "recording") -> None:
        self.where = where
        self._records = iter(records)
        self.head: Record | None = None
        self.head_line = 0  # the line of ``head`` in the file
        self.line = 0  # the line of the input last taken
        self.count = 0  # inputs taken
        self.end: Record | None = None
        self.failure: ConfigError | None = None
        self._next()

    @classmethod
    def of(cls, records: Iterable[Record]) -> Feed:
        """A feed of records held in memory (numbered from 2, as after a header)."""
        return cls(enumerate(records, start=2))

    def _next(self) -> None:
        self.head = None
        if self.failure is not None:
            return
        try:
            found = next(self._records, None)
            if found is not None and found[1][0] == "end":
                self.end = found[1]
                found = next(self._records, None)  # nothing after it (the reader says so)
        except ConfigError as exc:
            self.fail(exc)
            return
        if found is not None:
            self.head_line, self.head = found

    def take(self) -> Record:
        """The next input, taken (``head`` must not be None)."""
        record = self.head
        assert record is not None
        self.line = self.head_line
        self.count += 1
        self._next()
        return record

    def fail(self, error: ConfigError) -> None:
        """The replay is refused (the first reason is kept): no input is delivered more."""
        if self.failure is None:
            self.failure = error
        self.head = None

    def refuse(self, line: int, text: str) -> None:
        self.fail(RecordingError(f"{self.where}: line {line}: {text}"))

    def close(self) -> None:
        close = getattr(self._records, "close", None)
        if close is not None:
            close()


class ReplayRunner(Runner):
    """A runner fed by recorded inputs (see the module docstring)."""

    def __init__(
        self,
        clock: ReplayClock,
        speed: float | None,
        inputs: Feed | Iterable[Record],
        wall: WallClock | None = None,
        limit_us: int = MAX_SIM_US,
    ) -> None:
        super().__init__(clock, speed, wall=wall, report=lambda text: None)
        self.replay_clock = clock
        self.limit_us = limit_us  # the clock never runs past it (the recording's end)
        self.overrun: tuple[int, int] | None = None  # (line, t_us) of a run cut there
        self.command_lines: list[int] = []  # the lines of the commands running (nested)
        self.feed = inputs if isinstance(inputs, Feed) else Feed.of(inputs)
        self.out: Outputs = []  # or a Comparer: what the replay produces goes there
        self.dispatch: Dispatch | None = None  # commands and binds (fieldtwin.replay)
        self.keys = Keys()
        self._handlers: dict[str, tuple[Transport, DataCallback, CloseCallback | None]] = {}
        self._listening: dict[str, tuple[Listener, ConnectCallback]] = {}
        self._key_of: dict[int, str] = {}

    # --- attachments: named as the recorder named them; nothing is watched ----------

    def attach(
        self, transport: Transport, on_data: DataCallback, on_close: CloseCallback | None = None
    ) -> None:
        self.detach(transport)
        key = self.keys.link()
        self._handlers[key] = (transport, on_data, on_close)
        self._key_of[id(transport)] = key
        if isinstance(transport, SendObservable):  # what it sends is an output
            transport.observe_sends(partial(self._sent, key))

    def attach_listener(self, listener: Listener, on_connect: ConnectCallback) -> None:
        self.detach(listener)
        key = self.keys.listener()
        self._listening[key] = (listener, on_connect)
        self._key_of[id(listener)] = key

    def detach(self, transport_or_listener: Transport | Listener) -> None:
        key = self._key_of.pop(id(transport_or_listener), None)
        if key is not None:
            self._handlers.pop(key, None)
            self._listening.pop(key, None)

    def _sent(self, key: str, data: bytes) -> None:
        self.out.append(["send", self.clock.now, key, bytes(data).hex()])

    # --- runs -------------------------------------------------------------------------

    def advance(self, duration_us: int) -> None:
        if duration_us < 0:
            raise ConfigError(f"cannot advance by a negative time ({duration_us} us)")
        self._run(self.clock.now + duration_us, None)

    def play(self) -> None:
        """Deliver every input, in order (the top level: a stray ``ret`` is passed)."""
        feed = self.feed
        while feed.head is not None:
            if feed.head[0] == "ret":
                feed.take()
                continue
            self._run(None, None)

    def finish(self, t_us: int, fired: int | None) -> None:
        """Run on to where the recording ended."""
        if t_us >= self.clock.now and self.feed.failure is None:
            self._reach(t_us, fired, None)

    def take_ret(self) -> None:
        """A command returned: pass the recording's mark of its return, if it is next."""
        if self.feed.head is not None and self.feed.head[0] == "ret":
            self.feed.take()

    @property
    def stopping(self) -> bool:
        """A stop is asked, the replay has reached the recording's end or is refused (a
        console's stepped ``advance`` asks this between its steps)."""
        return self._stopping or self.overrun is not None or self.feed.failure is not None

    def _run(self, end: int | None, predicate: Callable[[], bool] | None) -> None:
        feed = self.feed
        if feed.failure is not None:  # refused: the plant runs no more
            return
        if end is not None and end > self.limit_us:
            # the recorded plant never ran past its end record: a command asking for more
            # (advance 1e9, a wait a changed plant never ends) stops there, and says so
            if self.overrun is None:
                line = self.command_lines[-1] if self.command_lines else feed.line
                self.overrun = (line, end)
            end = self.limit_us
        outer = self._stopping
        self._stopping = False
        try:
            while not self._stopping:
                if predicate is not None and predicate():
                    return
                record = feed.head
                if record is None:
                    break
                if record[0] == "ret" or (end is not None and record[1] > end):
                    break
                if record[1] < self.clock.now:  # a changed plant ran past it: at once
                    self._deliver_record(feed.take())
                    continue
                if not self._reach(record[1], record[2], predicate):
                    return
                if feed.head is not record:  # refused on the way (a damaged output line)
                    continue
                self._deliver_record(feed.take())
            if end is not None and not self._stopping and feed.failure is None:
                self._reach(end, None, predicate)
        finally:
            self._stopping = outer

    def _reach(self, t_us: int, fired: int | None, predicate: Callable[[], bool] | None) -> bool:
        """Run the events before ``t_us`` (instant by instant), those at it until ``fired``
        have run; stand at ``t_us``.  False if ``predicate`` came true on the way."""
        clock = self.replay_clock
        t_us = max(t_us, clock.now)
        while (deadline := clock.next_deadline()) is not None and deadline <= t_us:
            if deadline < t_us:
                clock.run_until(deadline)
            elif fired is None or clock.fired < fired:
                clock.run_one()
            else:
                break
            if predicate is not None and predicate():
                return False
        clock.stand_at(t_us)
        return True

    def _deliver_record(self, record: Record) -> None:
        kind, now = record[0], self.clock.now
        if kind == "data":
            handler = self._handlers.get(record[3])
            if handler is None:
                self._lost(record, "the replayed plant has no such transport")
                return
            handler[1](bytes.fromhex(record[4]), now)
        elif kind == "accept":
            listening = self._listening.get(record[3])
            if listening is None or not isinstance(listening[0], VirtualListener):
                self._lost(record, "the replayed plant has no such listener")
                return
            listening[1](listening[0].connection(), now)
        elif kind == "close":
            handler = self._handlers.get(record[3])
            if handler is None:
                self._lost(record, "the replayed plant has no such transport")
                return
            self.detach(handler[0])
            if handler[2] is not None:
                handler[2](now)
        elif kind == "settings":  # the master set its line: the pty shows it from now on
            handler = self._handlers.get(record[3])
            if handler is None or not isinstance(handler[0], PtyTransport):
                self._lost(record, "the replayed plant has no such pty")
                return
            handler[0].note_line(PeerLine(record[4], record[5], record[6]))
        elif self.dispatch is not None:
            self.dispatch(record)

    def _lost(self, record: Record, why: str) -> None:
        self.out.append(["lost", self.clock.now, record[0], record[3], why])


__all__ = [
    "Comparer",
    "Difference",
    "Feed",
    "ReplayClock",
    "ReplayRunner",
    "compare",
    "show",
]
