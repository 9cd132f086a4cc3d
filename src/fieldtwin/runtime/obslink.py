"""The observers' process, seen from the plant's (DESIGN rule 13; docs/architecture.md).

``fieldtwin run`` starts the bus with ``start(ObserversProcess.start)``: a child process
(``python -m fieldtwin.runtime.obsproc``, a fresh interpreter, not a fork of this
threaded one) is started, and the bus's observers' thread only ships each batch of
raw records down the child's stdin (``ship``: the lost count and the records, one
pickle behind a 4-byte length).  The child frames and decodes, builds the events,
writes the trace and pcap files, and runs one filter per ``/events`` subscriber
(``subscribe``); it answers on its stdout with, per subscriber, the JSON texts of its
events and what it dropped, which a reader thread here puts in that subscriber's
bounded queue (``RemoteSubscription``: its oldest dropped and counted when full) and
the web server's loop sends as they are.

The child ends when its stdin closes (``close``, or this process's end however it
comes: it never outlives us); ``close`` waits for it ``STOP_WAIT_S`` at most, so that
its files are complete when ``fieldtwin run`` exits.  If it cannot start, or dies,
this is said once on stderr and the bus works on its own thread, as before (new
subscriptions are served here; the files it held stop).
"""

from __future__ import annotations

import pickle
import struct
import subprocess
import sys
import threading
from collections import deque
from collections.abc import Callable, Collection
from typing import IO, Any

from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.obsrecords import OP_SUB, OP_UNSUB, OP_WRITE

STOP_WAIT_S = 10.0  # close() waits this long for the process to write its files and end
HEADER = struct.Struct(">I")  # the length of each message, both ways
MODULE = "fieldtwin.runtime.obsproc"
SHIP = 1024  # records per message down the pipe at most


def say(text: str) -> None:
    print(f"fieldtwin: {text}", file=sys.stderr, flush=True)


def write_message(out: IO[bytes], data: bytes) -> None:
    out.write(HEADER.pack(len(data)))
    out.write(data)
    out.flush()


def read_message(inp: IO[bytes]) -> bytes | None:
    """One message, or None at the end of the stream."""
    head = inp.read(HEADER.size)
    if len(head) < HEADER.size:
        return None
    (size,) = HEADER.unpack(head)
    data = inp.read(size)
    return data if len(data) == size else None


class RemoteSubscription:
    """An ``/events`` subscriber whose events the observers' process filters and
    encodes: ``texts()`` gives their JSON as it came (see fieldtwin.runtime.events's
    ``Subscription``: the same bounded queue, the oldest dropped and counted)."""

    def __init__(
        self,
        link: ObserversProcess,
        number: int,
        kinds: Collection[str] | None,
        devices: Collection[str] | None,
        maxlen: int,
        notify: Callable[[], None] | None,
    ) -> None:
        self._link = link
        self.number = number
        self.kinds = frozenset(kinds) if kinds else None
        self.devices = frozenset(devices) if devices else None
        self._queue: deque[str] = deque(maxlen=maxlen)
        self._lock = threading.Lock()
        self._notify = notify
        self.dropped = 0
        self.closed = False

    def _put(self, texts: list[str], dropped: int) -> None:
        """The reader thread: what the process sent for this subscriber."""
        queue = self._queue
        with self._lock:
            over = len(queue) + len(texts) - (queue.maxlen or 0)
            self.dropped += dropped + max(0, over)
            queue.extend(texts)
        if self._notify is not None:
            self._notify()

    def texts(self, limit: int = 1000) -> list[str]:
        """Up to ``limit`` events' JSON texts, oldest first (never blocks)."""
        with self._lock:
            count = min(limit, len(self._queue))
            return [self._queue.popleft() for _ in range(count)]

    def __len__(self) -> int:
        return len(self._queue)

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self._link.unsubscribe(self)


class ObserversProcess:
    """The child process of the observers and the two threads' ends of its pipes."""

    def __init__(self, bus: EventBus, proc: subprocess.Popen[bytes]) -> None:
        self.bus = bus
        self.proc = proc
        self.alive = True
        self._subs: dict[int, RemoteSubscription] = {}
        self._lock = threading.Lock()  # the subscriptions' table
        self._reader = threading.Thread(
            target=self._read, name="fieldtwin-observers-in", daemon=True
        )
        self._reader.start()

    @classmethod
    def start(cls, bus: EventBus) -> ObserversProcess | None:
        """The process started, or None (said: the bus's thread works instead)."""
        try:
            proc = subprocess.Popen(
                [sys.executable, "-m", MODULE],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                start_new_session=True,  # a Ctrl-C at the terminal is the plant's to handle
            )
        except OSError as exc:
            say(f"the observers' process did not start ({exc}): observing in this process")
            return None
        return cls(bus, proc)

    # --- the observers' thread -----------------------------------------------------

    def ship(self, batch: list[tuple[Any, ...]], lost: int) -> None:
        """One batch of raw records down the pipe (blocks while the process is behind:
        the bus's buffer fills meanwhile, then loses records, counted)."""
        for start in range(0, max(1, len(batch)), SHIP):
            if not self.alive:
                return
            self._ship(batch[start : start + SHIP], 0 if start else lost)

    def _ship(self, batch: list[tuple[Any, ...]], lost: int) -> None:
        try:
            data = pickle.dumps((lost, batch), protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, TypeError, AttributeError):
            data = pickle.dumps((lost, _picklable(batch)), protocol=pickle.HIGHEST_PROTOCOL)
        stdin = self.proc.stdin
        assert stdin is not None
        try:
            write_message(stdin, data)
        except (OSError, ValueError) as exc:
            self._died(f"the observers' process stopped taking records ({exc})")

    # --- subscriptions and files ---------------------------------------------------

    def subscribe(
        self,
        kinds: Collection[str] | None,
        devices: Collection[str] | None,
        maxlen: int,
        notify: Callable[[], None] | None,
    ) -> RemoteSubscription:
        number = self.bus.new_id()
        sub = RemoteSubscription(self, number, kinds, devices, maxlen, notify)
        with self._lock:
            self._subs[number] = sub
        self.bus.remote += 1
        self.bus.control((OP_SUB, number, _listed(kinds), _listed(devices), maxlen))
        return sub

    def unsubscribe(self, sub: RemoteSubscription) -> None:
        with self._lock:
            if self._subs.pop(sub.number, None) is None:
                return
        self.bus.remote -= 1
        self.bus.control((OP_UNSUB, sub.number))

    def write(self, kind: str, path: str, start_wall: float | None = None) -> None:
        """The process writes ``kind`` ("trace", "pcap") to ``path`` from now on."""
        self.bus.remote += 1
        self.bus.control((OP_WRITE, kind, path, start_wall))

    # --- the reader thread ---------------------------------------------------------

    def _read(self) -> None:
        stdout = self.proc.stdout
        assert stdout is not None
        while True:
            try:
                data = read_message(stdout)
            except (OSError, ValueError):
                data = None
            if data is None:
                break
            for number, texts, dropped in pickle.loads(data):
                with self._lock:
                    sub = self._subs.get(number)
                if sub is not None:
                    sub._put(texts, dropped)
        self._died("the observers' process ended")  # said only if not our own close

    def _died(self, why: str) -> None:
        if self.alive:
            self.alive = False
            say(f"{why}: its files stop, new subscribers are served in this process")

    def close(self) -> None:
        """The process's stdin closed: it writes what it holds, closes its files and
        ends; waited for ``STOP_WAIT_S`` at most, then killed."""
        proc = self.proc
        was_alive, self.alive = self.alive, False
        try:
            if proc.stdin is not None:
                proc.stdin.close()
        except OSError:
            pass
        try:
            proc.wait(STOP_WAIT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(STOP_WAIT_S)
            if was_alive:
                say(f"the observers' process did not end within {STOP_WAIT_S:g} s: killed")
        self._reader.join(STOP_WAIT_S)
        if proc.stdout is not None:
            proc.stdout.close()


def _listed(values: Collection[str] | None) -> list[str] | None:
    return sorted(values) if values else None


def _picklable(batch: list[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
    """The records of ``batch`` that pickle (a device published an odd value: its
    event is left out, said once)."""
    kept = []
    for record in batch:
        try:
            pickle.dumps(record)
        except (pickle.PicklingError, TypeError, AttributeError) as exc:
            if not _SAID:
                _SAID.add("unpicklable")
                say(f"an event could not go to the observers' process ({exc}): left out")
            continue
        kept.append(record)
    return kept


_SAID: set[str] = set()  # what was said once already


__all__ = ["ObserversProcess", "RemoteSubscription", "read_message", "write_message"]
