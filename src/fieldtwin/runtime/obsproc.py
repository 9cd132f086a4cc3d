"""The observers' process: ``python -m fieldtwin.runtime.obsproc`` (started by
fieldtwin.runtime.obslink, never by hand).

It reads batches of raw records on its stdin (``(lost, records)`` pickled behind a
4-byte length; the records are fieldtwin.runtime.events's ``OP_*``), and does with
them, on a bus of its own, what the observers' thread would have done in the plant's
process: wiretaps rebuilt from their ``spec`` frame and decode the bytes
(fieldtwin.runtime.wiretap), the events are built, the trace and pcap writers write
their files (byte for byte as in the plant's process), and each ``/events``
subscriber's filter keeps its events.  After each batch it answers on its stdout with
``[(subscriber, [JSON text, ...], dropped), ...]``.

It ends at the end of its stdin (the plant's process closed it, or ended): the files
are flushed and closed then.  A Ctrl-C at the terminal is not its business.  An error
is said once on stderr; the plant runs on.
"""

from __future__ import annotations

import pickle
import signal
import sys
from typing import IO, Any

from fieldtwin.runtime.events import EventBus, Subscription
from fieldtwin.runtime.obslink import read_message, say, write_message
from fieldtwin.runtime.obsrecords import (
    OP_IN,
    OP_OUT,
    OP_STREAM,
    OP_SUB,
    OP_TAP,
    OP_UNSUB,
    OP_WRITE,
)
from fieldtwin.runtime.pcap import PcapWriter
from fieldtwin.runtime.trace import TraceWriter
from fieldtwin.runtime.wiretap import Wiretap

ANSWER_EVERY = 256  # records handled between two answers (the events' latency stays low)


class Observers:
    """The bus of the observers' process and what hangs on it."""

    def __init__(self) -> None:
        self.bus = EventBus()  # never started: each record is handled at once
        self.bus.deferred = True  # ... and the subscribers woken once a batch
        self.taps: dict[int, Wiretap] = {}
        self.subs: dict[int, tuple[Subscription, list[int]]] = {}  # number -> (sub, [told])
        self.writers: list[TraceWriter | PcapWriter] = []
        self.failed = False

    def batch(self, lost: int, records: list[tuple[Any, ...]]) -> None:
        bus = self.bus
        if lost:
            for sub in bus._subs:
                sub._lost(lost)
        streams = bus._streams
        for record in records:
            try:
                op = record[0]
                if op == OP_IN:  # the two usual records straight to their stream
                    stream = streams.get(record[1])
                    if stream is not None:
                        stream.inbound(record[2], record[3], record[4])
                elif op == OP_OUT:
                    stream = streams.get(record[1])
                    if stream is not None:
                        stream.outbound(record[2], record[3])
                elif op < OP_TAP:
                    bus.handle(record)
                else:
                    self.control(record)
            except Exception as exc:  # a decoder's bug: told once, the plant runs on
                if not self.failed:
                    self.failed = True
                    say(f"an observer failed ({exc!r}); said once")
        bus.wake()

    def control(self, record: tuple[Any, ...]) -> None:
        op = record[0]
        if op == OP_TAP:
            self.taps[record[1]] = Wiretap.from_spec(self.bus, record[2])
        elif op == OP_STREAM:
            _, number, tap, conn = record
            self.taps[tap].stream(conn, number)
        elif op == OP_SUB:
            _, number, kinds, devices, maxlen = record
            self.subs[number] = (self.bus.subscribe(kinds, devices, maxlen=maxlen), [0])
        elif op == OP_UNSUB:
            sub = self.subs.pop(record[1], None)
            if sub is not None:
                sub[0].close()
        elif op == OP_WRITE:
            self.write(*record[1:])

    def write(self, kind: str, path: str, start_wall: float | None) -> None:
        try:
            if kind == "trace":
                self.writers.append(TraceWriter(self.bus, path, report=say))
            else:
                self.writers.append(
                    PcapWriter(self.bus, path, report=say, start_wall=start_wall, rtu_lines=True)
                )
        except Exception as exc:  # ConfigError: checked by the plant's process already
            say(str(exc))

    def answers(self) -> list[tuple[int, list[str], int]]:
        out = []
        for number, (sub, told) in self.subs.items():
            texts = sub.texts(len(sub))
            dropped = sub.dropped - told[0]
            if texts or dropped:
                told[0] = sub.dropped
                out.append((number, texts, dropped))
        return out

    def close(self) -> None:
        for writer in self.writers:
            writer.close()


def serve(inp: IO[bytes], out: IO[bytes]) -> None:
    observers = Observers()
    try:
        while True:
            data = read_message(inp)
            if data is None:
                break
            lost, records = pickle.loads(data)
            for start in range(0, max(1, len(records)), ANSWER_EVERY):
                observers.batch(lost if not start else 0, records[start : start + ANSWER_EVERY])
                answers = observers.answers()
                if answers:
                    try:
                        write_message(out, pickle.dumps(answers, pickle.HIGHEST_PROTOCOL))
                    except (OSError, ValueError):
                        observers.subs.clear()  # nobody reads: the files still get written
    finally:
        observers.close()


def main() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the plant's process ends us (EOF)
    inp, out = sys.stdin.buffer, sys.stdout.buffer
    sys.stdout = sys.stderr  # a stray print never corrupts the answers
    serve(inp, out)


if __name__ == "__main__":
    main()
