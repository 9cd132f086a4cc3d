"""What watching costs, in instructions per request: the observers' work on a fixed batch.

``benchmarks/observers.py`` measures throughput on a loaded 2-core machine, where the
ratios swing with everything else that runs; this script counts instructions
(benchmarks/counts.py: perf or callgrind), which the machine's load does not move.
Each part is a fixed workload run at two sizes (N and 5N requests) in a fresh
process; the difference per request is printed:

* ``trace``, ``pcap``, ``sub1``, ``sub4``: the observers' process
  (fieldtwin.runtime.obsproc ``serve``) fed the pickled messages the plant's process
  would send it (written to a file beforehand, not counted): a trace writer, a pcap
  writer, one or four ``/events`` subscriptions of every kind with their answers;
* ``post``: the simulation's thread: a real TES 32EST's wiretap (``seen_in``,
  ``seen_out``: the raw records and the TES states) on a started bus's buffer;
* ``ship``: the same and the plant's observers' thread: the buffer taken and pickled
  for the pipe (``post`` and ``ship`` less the workload's own loop over the traffic);
* ``reader1``: the plant's reader thread and the web server for one subscriber: the
  child's answers unpickled into the subscription's queue, taken and joined into the
  ``batch=1`` messages.

The traffic is what ``observers.py`` sends (``--traffic fc03``: 8 connections, FC03
x 10 words at 37, the transaction numbers counting up per connection, the words'
values changing now and then), or a mix (``mix``: FC03 at 37 and at 0, FC16 x 10 at
37, each a third).

    .venv/bin/python benchmarks/observer_counts.py [--parts trace,pcap] [--traffic fc03]
"""

from __future__ import annotations

import argparse
import io
import os
import pickle
import sys
import tempfile
from collections import deque
from pathlib import Path
from typing import Any

from fieldtwin.runtime.obslink import RemoteSubscription, read_message, write_message
from fieldtwin.runtime.obsrecords import OP_IN, OP_OUT, OP_STREAM, OP_SUB, OP_TAP, OP_WRITE

PARTS = ("trace", "pcap", "sub1", "sub4", "post", "ship", "reader1")
CHILD = ("trace", "pcap", "sub1", "sub4")
SMALL, LARGE = 400, 2000  # requests of the two counted workloads
CONNS = 8
PER_MESSAGE = 128  # records a message: about what 5 ms of 13k requests/s gathers
ENDPOINT = "tcp://127.0.0.1:15020"
NAME = "TES 32EST #1"
SPEC = (ENDPOINT, "tcp", ((1, NAME),), None, ENDPOINT)
START_WALL = 1_796_318_177.25


def _mbap(transaction: int, pdu: bytes) -> bytes:
    return (
        transaction.to_bytes(2, "big")
        + b"\x00\x00"
        + (len(pdu) + 1).to_bytes(2, "big")
        + b"\x01"
        + pdu
    )


def traffic(requests: int, kind: str) -> list[tuple[int, bytes, bytes, int]]:
    """(connection, request, reply, simulated us) of each request, in order."""
    out = []
    for n in range(requests):
        conn, transaction = n % CONNS, (n // CONNS + 1 + 4096 * (n % CONNS)) & 0xFFFF
        which = n % 3 if kind == "mix" else 0
        value = n // 50  # the words change now and then, as inputs do
        words = b"".join((value + i).to_bytes(2, "big") for i in range(10))
        if which == 2:  # write 10 words at 37: the echo
            pdu = bytes.fromhex("100025000a14") + words
            answer = bytes.fromhex("100025000a")
        else:
            address = 37 if which == 0 else 0
            pdu = bytes((3,)) + address.to_bytes(2, "big") + b"\x00\x0a"
            answer = b"\x03\x14" + words
        out.append((conn, _mbap(transaction, pdu), _mbap(transaction, answer), 1000 * n))
    return out


def records(requests: int, kind: str) -> list[tuple[Any, ...]]:
    """The raw records the plant's process would send: the wiretap, its streams, then
    per request its chunk in and its reply out (the TES answers: states ``(None,)``)."""
    out: list[tuple[Any, ...]] = [(OP_TAP, 1, SPEC)]
    out += [(OP_STREAM, 10 + c, 1, f"127.0.0.1:{40000 + c}") for c in range(CONNS)]
    for conn, request, answer, now in traffic(requests, kind):
        out.append((OP_IN, 10 + conn, request, now, (None,)))
        out.append((OP_OUT, 10 + conn, answer, now))
    return out


def messages(part: str, requests: int, kind: str, tmp: Path) -> bytes:
    """The child's stdin for ``part``: its subscriptions or file first, then the data."""
    head: list[tuple[Any, ...]] = []
    if part == "trace":
        head = [(OP_WRITE, "trace", str(tmp / "t.jsonl"), None)]
    elif part == "pcap":
        head = [(OP_WRITE, "pcap", str(tmp / "t.pcap"), START_WALL)]
    elif part.startswith("sub"):
        head = [(OP_SUB, 100 + i, None, None, 10_000) for i in range(int(part[3:]))]
    data = head + records(requests, kind)
    out = io.BytesIO()
    for start in range(0, len(data), PER_MESSAGE):
        write_message(out, pickle.dumps((0, data[start : start + PER_MESSAGE]), 5))
    return out.getvalue()


# --- the workloads (counted) ------------------------------------------------------------


def workload(part: str, requests: int, kind: str, data: str | None) -> None:
    if part in CHILD:
        from fieldtwin.runtime.obsproc import serve

        assert data is not None
        with open(data, "rb") as inp:
            serve(io.BufferedReader(inp), io.BytesIO())  # type: ignore[arg-type]
    elif part == "post":
        _post(requests, kind, ship=False)
    elif part == "ship":
        _post(requests, kind, ship=True)
    elif part == "loop":
        _post(requests, kind, ship=False, tapped=None)
    elif part == "reader1":
        assert data is not None
        _reader(data)
    print(f"units {requests}")


class _Pipe:
    """A link whose pipe is a buffer (the observers' thread's side of ``ship``)."""

    alive = True

    def __init__(self) -> None:
        self.out = io.BytesIO()

    def ship(self, batch: list[tuple[Any, ...]], lost: int) -> None:
        write_message(self.out, pickle.dumps((lost, batch), pickle.HIGHEST_PROTOCOL))
        self.out.seek(0)
        self.out.truncate()

    def close(self) -> None:
        pass


def _post(requests: int, kind: str, ship: bool, tapped: bool | None = True) -> None:
    """The simulation's side: a TES 32EST's wiretap on a bus whose buffer is taken every
    ``PER_MESSAGE`` records; ``ship``: and pickled (else the buffer is only emptied)."""
    from fieldtwin.clock import SimClock
    from fieldtwin.modbus.model import Link
    from fieldtwin.modbus.slave import SlaveSet
    from fieldtwin.runtime.events import EventBus
    from fieldtwin.runtime.wiretap import Wiretap
    from fieldtwin.tes import Tes

    bus = EventBus()
    pipe = _Pipe()
    bus._link = pipe  # type: ignore[assignment]  # started by hand: no thread, counted alone
    bus.remote = 1  # a subscriber in the observers' process
    bus._feed = deque()
    tes = Tes("32EST", 1, clock=SimClock())
    tap = Wiretap(bus, ENDPOINT, "tcp", SlaveSet([tes], Link.TCP), None, ENDPOINT)
    streams = [tap.stream(f"127.0.0.1:{40000 + c}") for c in range(CONNS)]
    feed = bus._feed
    for conn, request, answer, now in traffic(requests, kind):
        if tapped is None:  # the loop alone: what ``post`` and ``ship`` take off
            continue
        stream = streams[conn]
        stream.seen_in(request, now)
        stream.seen_out(answer, now)
        if len(feed) >= PER_MESSAGE:
            if ship:
                bus.process()
            else:
                feed.clear()


def reader_messages(requests: int, kind: str) -> bytes:
    """What the observers' process answers one subscriber of every kind (not counted)."""
    from fieldtwin.runtime.obsproc import Observers

    observers = Observers()
    observers.control((OP_SUB, 100, None, None, 10_000))
    out = io.BytesIO()
    data = records(requests, kind)
    for start in range(0, len(data), PER_MESSAGE):
        observers.batch(0, data[start : start + PER_MESSAGE])
        write_message(out, pickle.dumps(observers.answers(), pickle.HIGHEST_PROTOCOL))
    return out.getvalue()


def _reader(data: str) -> None:
    """The plant's reader thread and the web server's sends for one subscriber."""

    class _Link:
        def unsubscribe(self, sub: Any) -> None:
            pass

    sub = RemoteSubscription(_Link(), 100, None, None, 10_000, None)  # type: ignore[arg-type]
    sent: list[str] = []
    with open(data, "rb") as inp:
        while (message := read_message(inp)) is not None:
            for _number, texts, dropped in pickle.loads(message):
                sub._put(texts, dropped)
            while len(sub):
                sent.append("[" + ",".join(sub.texts(500)) + "]")
            sent.clear()


# --- the harness ------------------------------------------------------------------------


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", default=",".join(PARTS), help="comma list of " + ",".join(PARTS))
    parser.add_argument("--traffic", default="fc03", choices=("fc03", "mix"))
    parser.add_argument("--workload", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--part", help=argparse.SUPPRESS)
    parser.add_argument("--data", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.workload is not None:
        workload(args.part, args.workload, args.traffic, args.data)
        return
    sys.path.insert(0, str(Path(__file__).parent))
    from counts import count, tool

    parts = [p for p in args.parts.split(",") if p]
    unknown = set(parts) - set(PARTS)
    if unknown:
        raise SystemExit(f"--parts: any of {', '.join(PARTS)}")
    loop: float | None = None  # instructions per request of the post workload's own loop
    with tempfile.TemporaryDirectory(prefix="obscounts_") as tmp:
        for part in parts:
            counted = []
            for size in (SMALL, LARGE):
                argv = [sys.executable, __file__, "--workload", str(size), "--part", part]
                argv += ["--traffic", args.traffic]
                if part in CHILD or part == "reader1":
                    path = Path(tmp) / f"{part}-{size}.bin"
                    if part == "reader1":
                        path.write_bytes(reader_messages(size, args.traffic))
                    else:
                        path.write_bytes(messages(part, size, args.traffic, Path(tmp)))
                    argv += ["--data", str(path)]
                counted.append(count(argv))
            small, large = counted
            per = (large.instructions - small.instructions) / (large.units - small.units)
            if part in ("post", "ship"):  # the workload's own loop taken off
                if loop is None:
                    argv = [sys.executable, __file__, "--part", "loop", "--traffic", args.traffic]
                    a = count([*argv, "--workload", str(SMALL)])
                    b = count([*argv, "--workload", str(LARGE)])
                    loop = (b.instructions - a.instructions) / (b.units - a.units)
                per -= loop
            print(
                f"{part:<8} {per:>10,.0f} instructions per request ({tool()}, {args.traffic})",
                flush=True,
            )
            for name in os.listdir(tmp):
                if not name.endswith(".bin"):
                    os.unlink(Path(tmp) / name)


if __name__ == "__main__":
    main()
