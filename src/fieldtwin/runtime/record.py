"""Recording a whole plant session: everything that enters it, everything it emits.

``fieldtwin run --record FILE`` and ``plant.record(FILE)`` write one file
(docs/record.md): a gzip stream of JSON lines, the first a header (format and
version, the plant file's text and every file it names - PL7 programs, TES
parameter stores, csv signals - the speed, the sampling period), then one
compact JSON array per record, in the order things happened:

inputs (with the simulated instant and ``fired``, how many clock events had run
before them, so that a replay delivers them between the very same two events)::

    ["bind",   t, fired, ["modbus", "scm"]]   ports opened (binder groups)
    ["accept", t, fired, "l1"]                a connection on listener l1
    ["data",   t, fired, "t3", "0001..."]     bytes that arrived on transport t3
    ["close",  t, fired, "t3"]                the peer closed t3
    ["call",   t, fired, "set_input", [...]]  a control-API command (Control method)
    ["line",   t, fired, "advance 5"]         a console command line
    ["ret",    t, fired]                      the command before returned here

outputs (the simulated instant only; a replay must produce them identically)::

    ["send",   t, "t3", "0001..."]            bytes sent on transport t3
    ["result", t, "set_input", {...}]         what a command answered
    ["object", t, "5", "IW5,0", 4104]         an object changed (sampled)
    ["led",    t, "5", "ERR", "on"]           an LED changed (sampled)
    ["chars",  t, "7", 0, "out", "48454c4c4f"] SCM characters (a block, wiretap.CharTap)
    ["dem",    t, "4", "1994-07-15 18:06:45.000", "change", 0, 1, true]
                                              a DEM message logged (stamp, type, channel,
                                              state or words, stored)
    ["end",    t, fired]                      the recording was closed here

Transports and listeners are named by the order the runner was given them
(``t1``, ``t2``..., ``l1``...): the binder opens them in the plant file's order,
so a replay that binds the same plant names them the same, whatever ports and
pty paths the recording got.  Objects and LEDs are looked at (peeked, never
read) every ``sample_ms`` of simulated time by a clock event of the recorder's
own, which both the recording and its replay have.

The simulation's thread only appends each record, raw (the bytes as bytes), to the
writer's bounded queue (``QUEUE`` records); the writer's thread turns them into JSON
(bytes into hex), compresses and writes them, in order.  A recording is an input log
and stays complete: when its writer falls behind and the queue is full, the plant
waits for it (the time waited is told when the recording closes; docs/record.md).
"""

from __future__ import annotations

import gzip
import json
import threading
import time
from collections import deque
from collections.abc import Callable, Collection, Generator, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fieldtwin import __version__
from fieldtwin.clock import MS, Handle, SimClock
from fieldtwin.devices.face import Device, peeker
from fieldtwin.devices.module import ModuleDevice, PlcObjects
from fieldtwin.errors import ConfigError, FieldtwinError
from fieldtwin.runtime.events import Event, EventBus
from fieldtwin.runtime.recfile import (
    FORMAT,
    INPUT_KINDS,
    MAX_HEADER_BYTES,
    OUTPUT_KINDS,
    VERSION,
    MiB,
    Record,
    check_header,
    header_data,
)
from fieldtwin.runtime.recfile import records as numbered_records
from fieldtwin.runtime.runner import CloseCallback, ConnectCallback, DataCallback, Runner
from fieldtwin.transports.base import Listener, Transport

SAMPLE_MS = 100  # objects and LEDs are looked at this often (simulated ms)
SAMPLE_PRIORITY = 1 << 30  # after every plant event of the same instant
MAX_OBJECTS = 4096  # objects one device is looked at for
INPUTS = INPUT_KINDS
OUTPUTS = OUTPUT_KINDS

ORIGINAL_SEND = "_fieldtwin_unrecorded_send"  # where a recorded transport keeps its send
QUEUE = 50_000  # records handed to the writer and not yet written: past it the plant waits
WRITE_BATCH = 2000  # records the writer's thread turns into one compressed write
WRITE_S = 0.01  # the writer's thread takes what was queued this often


@dataclass(frozen=True, slots=True)
class Header:
    """What a recording starts with."""

    plant_name: str
    plant_text: str
    files: Mapping[str, str]  # a name the plant file gives -> that file's text (latin-1)
    speed: float | None
    sample_ms: int
    version: int = VERSION
    fieldtwin: str = __version__
    console: str = "inline"  # how its console lines ran: one of recfile.CONSOLES

    def as_json(self) -> dict[str, object]:
        return {
            "format": FORMAT,
            "version": self.version,
            "fieldtwin": self.fieldtwin,
            "plant": {"name": self.plant_name, "text": self.plant_text, "files": dict(self.files)},
            "speed": self.speed,
            "sample_ms": self.sample_ms,
            "console": self.console,
        }

    @classmethod
    def from_json(cls, data: object, where: str) -> Header:
        """The header of a recording, every field checked (fieldtwin.runtime.recfile)."""
        fields = check_header(data, where)
        plant, speed = fields["plant"], fields["speed"]
        return cls(
            plant["name"],
            plant["text"],
            dict(plant["files"]),
            None if speed is None else float(speed),
            fields["sample_ms"],
            fields["version"],
            fields["fieldtwin"],
            fields["console"],
        )


class Keys:
    """Names of transports and listeners in the order they are attached (t1.., l1..)."""

    def __init__(self) -> None:
        self._links = 0
        self._listeners = 0

    def link(self) -> str:
        self._links += 1
        return f"t{self._links}"

    def listener(self) -> str:
        self._listeners += 1
        return f"l{self._listeners}"


# ------------------------------------------------------------------------- the file


class RecordWriter:
    """A gzip file of JSON lines: the header, then the records, written by a thread of
    its own from a bounded queue (``add`` waits when the queue is full)."""

    def __init__(self, path: str | Path, header: Header) -> None:
        self.path = Path(path)
        size = len(_line(header.as_json()))
        if size > MAX_HEADER_BYTES:  # a replay would refuse it: say so now
            raise ConfigError(
                f"--record {path}: the plant file and the files it names make a header of"
                f" {size / MiB:.1f} MiB; a recording's header is at most"
                f" {MAX_HEADER_BYTES // MiB} MiB (docs/record.md)"
            )
        try:
            self._file: gzip.GzipFile | None = gzip.GzipFile(self.path, "wb", compresslevel=6)
        except OSError as exc:
            raise ConfigError(f"--record {path}: cannot write ({exc.strerror})") from None
        self.records = 0
        self.waited_s = 0.0  # how long the plant waited for the writer (a full queue)
        self.waits = 0
        self.failed: BaseException | None = None  # what stopped the writer's thread
        self._file.write(_line(header.as_json()))
        self._queue: deque[Record] = deque()
        self._room = threading.Condition()
        self._ending = False
        self._thread: threading.Thread | None = threading.Thread(
            target=self._write_all, name="fieldtwin-record", daemon=True
        )
        self._thread.start()

    def add(self, record: Record) -> None:
        """Hand one record to the writer (the simulation's thread): waits while the
        writer is ``QUEUE`` records behind."""
        if self._thread is None:
            return
        if self.failed is not None:
            raise self.failed
        pending = self._queue
        if len(pending) >= QUEUE:
            started = time.perf_counter()
            with self._room:
                while len(pending) >= QUEUE and self.failed is None:
                    self._room.wait(WRITE_S)
            self.waited_s += time.perf_counter() - started
            self.waits += 1
        self.records += 1
        pending.append(record)

    def _write_all(self) -> None:
        file, pending = self._file, self._queue
        assert file is not None
        while True:
            ending = self._ending
            if not ending:
                time.sleep(WRITE_S)  # a batch gathers: no wake-up per record
            while pending:
                count = min(WRITE_BATCH, len(pending))
                batch = [pending.popleft() for _ in range(count)]
                if self.failed is None:
                    try:
                        file.write(b"".join(_line(record) for record in batch))
                    except (OSError, ValueError) as exc:
                        self.failed = exc  # told on the next add() or on close()
                with self._room:
                    self._room.notify_all()
            if ending:
                return

    def close(self) -> None:
        """Write what is queued, then close the file (idempotent)."""
        thread, self._thread = self._thread, None
        if thread is not None:
            self._ending = True
            thread.join()
        if self._file is not None:
            file, self._file = self._file, None
            file.close()
        if self.failed is not None:
            failed, self.failed = self.failed, None
            raise failed


def _line(item: object) -> bytes:
    text = json.dumps(item, separators=(",", ":"), ensure_ascii=False, default=_plain)
    return text.encode("utf-8") + b"\n"


def _plain(value: object) -> object:
    """Bytes as hex (the simulation's thread hands them raw), anything else as text."""
    if isinstance(value, bytes | bytearray | memoryview):
        return bytes(value).hex()
    return str(value)


def read_recording(path: str | Path) -> tuple[Header, list[Record]]:
    """The header and the records of a recording, whole (a short one: tests, tools);
    errors name the file and the line."""
    return read_header(path), list(iter_records(path))


def read_header(path: str | Path) -> Header:
    return Header.from_json(header_data(path), str(path))


def iter_records(
    path: str | Path, kinds: Collection[str] | None = None
) -> Generator[Record, None, None]:
    """The records after the header, one at a time (of ``kinds`` only, when given): a
    recording of hours is never held in memory whole.  Every line is checked as
    untrusted input (fieldtwin.runtime.recfile): bounded, of its kind's form, in time
    order."""
    return (record for _, record in numbered_records(path, kinds))


# ------------------------------------------------------------------------- sampling


class Sampler:
    """Objects and LEDs of the devices, peeked every ``period_us``; changes to ``emit``."""

    def __init__(
        self,
        clock: SimClock,
        devices: Sequence[Device],
        emit: Callable[[Record], None],
        period_us: int,
    ) -> None:
        self.clock = clock
        self.devices = list(devices)
        self.emit = emit
        self.period_us = period_us
        self._seen: dict[tuple[str, str, str], object] = {}
        self._names: dict[int, list[tuple[str, Callable[[], object]]]] = {}
        self._timer: Handle | None = clock.schedule(clock.now, self._sample, SAMPLE_PRIORITY)

    def _sample(self, now: int) -> None:
        self.look(now)
        self._timer = self.clock.schedule(now + self.period_us, self._sample, SAMPLE_PRIORITY)

    def look(self, now: int) -> None:
        for device in self.devices:
            address = str(device.address)
            for name, state in device.status().leds:
                self._change(now, "led", address, name, str(state))
            for name, peek in self._peekers(device):
                try:
                    value: object = peek()
                except FieldtwinError:
                    value = None  # a module out of its slot, a word its model lacks
                self._change(now, "object", address, name, value)

    def _peekers(self, device: Device) -> list[tuple[str, Callable[[], object]]]:
        """(name, peek) of every object of ``device``, made once (an object that binds its
        peek, a TES word by its number: no name to parse on every look)."""
        found = self._names.get(id(device))
        if found is not None:
            return found
        objects = device.objects()
        names = [entry.address for entry in objects.names()[:MAX_OBJECTS]]
        if isinstance(device, ModuleDevice) and isinstance(objects, PlcObjects):
            # the module's own PL7 objects (its names): the PLC reads them, no side effect
            found = [(name, _bind(device.plc.read, name)) for name in names]
        else:
            found = [(name, peeker(objects, name)) for name in names]
        self._names[id(device)] = found
        return found

    def _change(self, now: int, kind: str, address: str, name: str, value: object) -> None:
        key = (kind, address, name)
        if key in self._seen and self._seen[key] == value:
            return
        self._seen[key] = value
        self.emit([kind, now, address, name, value])

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None


def _bind(peek: Callable[[Any], int], name: object) -> Callable[[], object]:
    return lambda: peek(name)


def chars_record(event: Event) -> Record:
    """The record of an SCM block or a DEM message published on the bus."""
    data = event.data
    if event.kind == "dem":  # a message a DEM logged (runtime.binder's logbook tap)
        what = [data["channel"], data["state"]] if data["type"] == "change" else [data["words"]]
        return ["dem", event.t_us, event.device, data["stamp"], data["type"], *what, data["stored"]]
    return ["chars", event.t_us, event.device, data.get("channel"), data.get("dir"), data["hex"]]


class CharsFeed:
    """SCM character blocks and DEM messages published on the plant's bus, as records,
    on the simulation's thread as they are published (``bus.listen``): in order with
    the bytes and commands recorded around them."""

    def __init__(self, bus: EventBus, emit: Callable[[Record], None]) -> None:
        self._emit = emit
        self._stop: Callable[[], None] | None = bus.listen(("serial", "dem"), self._heard)

    def _heard(self, t_us: int, kind: str, device: str, data: Mapping[str, object]) -> None:
        self._emit(chars_record(Event(t_us, kind, device, data)))

    def close(self) -> None:
        if self._stop is not None:
            self._stop()
            self._stop = None


# ------------------------------------------------------------------------- the recorder


class Recorder:
    """Writes what enters and leaves one plant (see the module docstring).

    Install it before any port opens (``runner.set_tap(recorder)`` wraps those
    already attached, in order); ``close()`` writes the end record and the file.
    """

    def __init__(
        self,
        path: str | Path,
        header: Header,
        clock: SimClock,
        devices: Sequence[Device],
        bus: EventBus,
        runner: Runner | None = None,
    ) -> None:
        self.clock = clock
        self.writer = RecordWriter(path, header)
        self.keys = Keys()
        self._depth = 0  # inside a recorded command: its inner calls are its own
        self.closed = False
        self._chars = CharsFeed(bus, self.writer.add)
        self._sampler = Sampler(clock, devices, self.writer.add, header.sample_ms * MS)
        if runner is not None:
            runner.set_tap(self)

    @property
    def path(self) -> Path:
        return self.writer.path

    def _input(self, kind: str, *fields: object) -> None:
        self.writer.add([kind, self.clock.now, self.clock.fired, *fields])

    # --- what the runner is given (fieldtwin.runtime.runner.AttachTap) --------------

    def link(
        self, transport: Transport, on_data: DataCallback, on_close: CloseCallback | None
    ) -> tuple[DataCallback, CloseCallback | None]:
        key = self.keys.link()
        # the instance's own send, wrapped once (attached again: the first send, a new key)
        send: Callable[[bytes], None] = getattr(transport, ORIGINAL_SEND, transport.send)

        def sending(data: bytes) -> None:
            self.writer.add(["send", self.clock.now, key, bytes(data)])  # hex: the writer's
            send(data)

        setattr(transport, ORIGINAL_SEND, send)
        setattr(transport, "send", sending)  # noqa: B010

        def arrived(data: bytes, now: int) -> None:
            self._input("data", key, bytes(data))  # hex: the writer's thread
            on_data(data, now)

        def closed(now: int) -> None:
            self._input("close", key)
            if on_close is not None:
                on_close(now)

        return arrived, closed

    def listener(self, listener: Listener, on_connect: ConnectCallback) -> ConnectCallback:
        key = self.keys.listener()

        def connected(transport: Transport, now: int) -> None:
            self._input("accept", key)
            on_connect(transport, now)

        return connected

    # --- what the binder, the console and the control API tell ----------------------

    def bound(self, groups: Sequence[str]) -> None:
        self._input("bind", sorted(groups))

    def command(self, kind: str, name: str, args: Sequence[object], run: Callable[[], Any]) -> Any:
        """Run a command (a console line, a control call), recording it and its answer."""
        if self._depth or self.closed:
            return run()
        self._input(kind, *([name] if kind == "line" else [name, list(args)]))
        label = "console" if kind == "line" else name
        self._depth += 1
        try:
            result = run()
        except FieldtwinError as exc:
            self._depth -= 1
            self._input("ret")
            self.writer.add(["result", self.clock.now, label, {"error": str(exc)}])
            raise
        except BaseException:
            self._depth -= 1
            raise
        self._depth -= 1
        self._input("ret")
        self.writer.add(["result", self.clock.now, label, plain_json(result)])
        return result

    def instrument(self, target: object, names: Sequence[str]) -> None:
        """Record every call of ``target``'s methods ``names`` (the control API's Control)."""
        for name in names:
            method = getattr(target, name)
            setattr(target, name, self._recorded(name, method))

    def _recorded(self, name: str, method: Callable[..., Any]) -> Callable[..., Any]:
        def call(*args: object) -> Any:
            return self.command("call", name, args, lambda: method(*args))

        return call

    def close(self) -> None:
        """The end record; the file closed (flushed).  Safe to call twice."""
        if self.closed:
            return
        self.closed = True
        self._chars.close()
        self._sampler.close()
        self.writer.add(["end", self.clock.now, self.clock.fired])
        self.writer.close()

    @property
    def waited(self) -> str | None:
        """What the plant waited for the writer, in words (None: it never did)."""
        writer = self.writer
        if not writer.waits:
            return None
        return (
            f"recording {writer.path}: the plant waited {writer.waited_s:.3f} s for its"
            f" writer ({writer.waits} times {QUEUE} records behind)"
        )


def plain_json(value: object) -> object:
    """A command's answer as JSON would give it back (tuples become lists)."""
    result: object = json.loads(json.dumps(value, default=str))
    return result


def inputs_and_outputs(records: Sequence[Record]) -> tuple[list[Record], list[Record]]:
    ins = [r for r in records if r[0] in INPUTS]
    outs = [r for r in records if r[0] in OUTPUTS]
    return ins, outs


def iter_outputs(records: Sequence[Record]) -> Iterator[Record]:
    return (r for r in records if r[0] in OUTPUTS)


__all__ = [
    "FORMAT",
    "SAMPLE_MS",
    "VERSION",
    "Header",
    "Keys",
    "Record",
    "RecordWriter",
    "Recorder",
    "Sampler",
    "chars_record",
    "inputs_and_outputs",
    "iter_records",
    "plain_json",
    "read_header",
    "read_recording",
]
