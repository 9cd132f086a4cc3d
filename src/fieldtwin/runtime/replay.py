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

``compare`` finds the first difference between two streams of output records
and shows it in context.
"""

from __future__ import annotations

import json
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Protocol

from fieldtwin.clock import SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.recfile import MAX_SIM_US, RecordingError
from fieldtwin.runtime.record import Keys, Record
from fieldtwin.runtime.runner import CloseCallback, ConnectCallback, DataCallback, Runner
from fieldtwin.runtime.wall import WallClock
from fieldtwin.transports.base import Listener, Transport
from fieldtwin.transports.virtual import VirtualListener

CONTEXT = 3  # records shown before and after a first difference


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
        if hasattr(transport, "sink"):  # a virtual transport: what it sends is an output
            setattr(transport, "key", key)  # noqa: B010
            setattr(transport, "sink", self._sent)  # noqa: B010

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
        self.out.append(["send", self.clock.now, key, data.hex()])

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
        elif self.dispatch is not None:
            self.dispatch(record)

    def _lost(self, record: Record, why: str) -> None:
        self.out.append(["lost", self.clock.now, record[0], record[3], why])


# ------------------------------------------------------------------------- comparing


@dataclass(frozen=True, slots=True)
class Difference:
    """Where two streams of outputs part, and the text that shows it."""

    index: int
    text: str


def show(record: Record | None) -> str:
    """One record as a line: ``t = 1.234567 s  send t3  00 01 00 00 00 06``."""
    if record is None:
        return "(nothing: the stream has ended)"
    kind, t_us, rest = record[0], record[1], record[2:]
    if kind == "send":
        return f"t = {t_us / 1e6:.6f} s  send {rest[0]}  {_spaced(rest[1])}"
    if kind == "chars":
        text = bytes.fromhex(rest[3]).decode("latin-1")
        return f"t = {t_us / 1e6:.6f} s  chars {rest[0]} channel {rest[1]} {rest[2]}  {text!r}"
    if kind in ("object", "led"):
        return f"t = {t_us / 1e6:.6f} s  {kind} {rest[0]} {rest[1]} = {rest[2]}"
    if kind == "dem":
        body = " ".join(str(r) for r in rest[3:-1])
        lost = "" if rest[-1] else " (lost: stack full)"
        return f"t = {t_us / 1e6:.6f} s  dem {rest[0]} {rest[2]} {body} at {rest[1]}{lost}"
    if kind == "result":
        return f"t = {t_us / 1e6:.6f} s  result of {rest[0]}: {json.dumps(rest[1])[:200]}"
    at = f"t = {t_us / 1e6:.6f} s"
    if kind in INPUT_FORMS and len(rest) >= 1:
        fired, fields = rest[0], rest[1:]
        return f"{at}  {INPUT_FORMS[kind](fields)}  (after {fired} clock events)"
    return f"{at}  {kind} " + " ".join(str(r) for r in rest)


def _call(fields: Sequence[object]) -> str:
    args = fields[1] if len(fields) > 1 and isinstance(fields[1], list) else []
    return f"control {fields[0]}({', '.join(json.dumps(a) for a in args)})"


INPUT_FORMS: dict[str, Callable[[Sequence[object]], str]] = {
    "data": lambda f: f"data {f[0]}  {_spaced(str(f[1]))}",
    "accept": lambda f: f"accept on {f[0]}",
    "close": lambda f: f"close {f[0]}",
    "bind": lambda f: f"bind {' '.join(str(g) for g in f[0])}",  # type: ignore[attr-defined]
    "line": lambda f: f"console {str(f[0])!r}",
    "call": _call,
    "ret": lambda f: "(the command returned)",
}


def _spaced(hex_text: str, limit: int = 64) -> str:
    data = bytes.fromhex(hex_text)
    text = data[:limit].hex(" ")
    return text + (f" ... ({len(data)} bytes)" if len(data) > limit else "")


def compare(
    expected: Sequence[Record],
    actual: Sequence[Record],
    *,
    names: tuple[str, str] = ("recorded", "replayed"),
) -> Difference | None:
    """The first difference of two output streams (same record, same instant), or None."""
    comparer = Comparer(iter(expected), names=names)
    for record in actual:
        comparer.append(record)
    return comparer.finish()


class Comparer:
    """Compares records as a replay produces them with the expected ones, one by one:
    only the context of the first difference is kept (bounded memory)."""

    def __init__(
        self,
        expected: Iterator[Record],
        *,
        names: tuple[str, str] = ("recorded", "replayed"),
        on_error: Callable[[ConfigError], None] | None = None,
    ) -> None:
        self._expected = expected
        self._on_error = on_error  # a damaged expected stream: told there, then it ends
        self.names = names
        self.expected = 0  # expected records seen (all of them once finished)
        self.produced = 0
        self._before: deque[Record] = deque(maxlen=CONTEXT)
        self.index: int | None = None
        self._left: Record | None = None
        self._right: Record | None = None
        self._after_right: list[Record] = []

    def _next(self) -> Record | None:
        try:
            record = next(self._expected, None)
        except ConfigError as exc:
            if self._on_error is None:
                raise
            self._on_error(exc)
            self._expected = iter(())
            return None
        if record is not None:
            self.expected += 1
        return record

    def append(self, record: Record) -> None:
        self.produced += 1
        if self.index is None:
            wanted = self._next()
            if wanted == record:
                self._before.append(record)
                return
            self.index, self._left, self._right = self.produced - 1, wanted, record
        elif len(self._after_right) < CONTEXT:
            self._after_right.append(record)

    def finish(self) -> Difference | None:
        """Once the replay has ended: the first difference, or None."""
        if self.index is None:
            wanted = self._next()
            if wanted is None:
                return None
            self.index, self._left, self._right = self.produced, wanted, None
        after_left: list[Record] = []
        while len(after_left) < CONTEXT and (record := self._next()) is not None:
            after_left.append(record)
        while self._next() is not None:  # how many there were, for the text
            pass
        names, index = self.names, self.index
        lines = [f"first difference at output {index + 1} (of {self.expected} {names[0]}):"]
        lines.extend(f"    same      {show(r)}" for r in self._before)
        width = max(len(n) for n in names)
        lines.append(f"  - {names[0]:<{width}} {show(self._left)}")
        lines.append(f"  + {names[1]:<{width}} {show(self._right)}")
        for name, after in zip(names, (after_left, self._after_right), strict=True):
            if after:
                lines.append(f"    then, {name}:")
                lines.extend(f"        {show(r)}" for r in after)
        return Difference(index, "\n".join(lines))


__all__ = ["Comparer", "Difference", "Feed", "ReplayClock", "ReplayRunner", "compare", "show"]
