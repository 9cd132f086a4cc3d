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
    ["call",   t, fired, "set_input", [...]]  a control-API command (a door Command)
    ["line",   t, fired, "advance 5"]         a console command line (a door Command)
    ["ret",    t, fired]                      the command before returned here
    ["settings", t, fired, "t3", 9600, 1, false]  the master on pty t3 set its line:
                                              baud (null: unnamed), stop bits, odd parity

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
What enters is seen where it enters: bytes and connections through the runner's
attach tap (``Recorder.link`` and ``listener``: the transport's ``observe_sends``
shows what the plant sends), commands through the plant's door
(fieldtwin.runtime.door: ``before`` and ``after`` each outermost command).  The
file itself is fieldtwin.runtime.recwriter's.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from fieldtwin.clock import MS, Handle, SimClock
from fieldtwin.devices.face import Device, peeker
from fieldtwin.devices.module import ModuleDevice, PlcObjects
from fieldtwin.errors import FieldtwinError
from fieldtwin.runtime.door import LINE, Command, Door
from fieldtwin.runtime.events import Event, EventBus
from fieldtwin.runtime.recfile import FORMAT, INPUT_KINDS, OUTPUT_KINDS, VERSION, Record
from fieldtwin.runtime.recwriter import (
    QUEUE,
    Header,
    Keys,
    RecordWriter,
    iter_records,
    read_header,
    read_recording,
)
from fieldtwin.runtime.runner import CloseCallback, ConnectCallback, DataCallback, Runner
from fieldtwin.transports.base import Listener, SendObservable, Transport
from fieldtwin.transports.pty import PeerLine, PtyTransport

SAMPLE_MS = 100  # objects and LEDs are looked at this often (simulated ms)
SAMPLE_PRIORITY = 1 << 30  # after every plant event of the same instant
MAX_OBJECTS = 4096  # objects one device is looked at for
INPUTS = INPUT_KINDS
OUTPUTS = OUTPUT_KINDS


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
    already attached, in order) and on the plant's door (``door``: it sees every
    outermost command); ``close()`` writes the end record and the file.
    """

    def __init__(
        self,
        path: str | Path,
        header: Header,
        clock: SimClock,
        devices: Sequence[Device],
        bus: EventBus,
        runner: Runner | None = None,
        *,
        door: Door | None = None,
    ) -> None:
        self.clock = clock
        self.writer = RecordWriter(path, header)
        self.keys = Keys()
        self.closed = False
        self._chars = CharsFeed(bus, self.writer.add)
        self._sampler = Sampler(clock, devices, self.writer.add, header.sample_ms * MS)
        self._observed: list[SendObservable] = []  # transports whose sends it sees
        self._lines: list[PtyTransport] = []  # ptys whose master's settings it sees
        self._unwatch: Callable[[], None] | None = None
        if runner is not None:
            runner.set_tap(self)
        if door is not None:
            self.watch(door)

    @property
    def path(self) -> Path:
        return self.writer.path

    def _input(self, kind: str, *fields: object) -> None:
        self.writer.add([kind, self.clock.now, self.clock.fired, *fields])

    # --- what the runner is given (fieldtwin.runtime.runner.AttachTap) --------------

    def link(
        self, transport: Transport, on_data: DataCallback, on_close: CloseCallback | None
    ) -> tuple[DataCallback, CloseCallback | None]:
        key = self.keys.link()  # attached again: a new key, its sends under it from now
        if isinstance(transport, SendObservable):
            transport.observe_sends(self._sending(key))
            self._observed.append(transport)

        if isinstance(transport, PtyTransport):  # the master's line settings: inputs too
            transport.observe_line(self._line_set(key))
            self._lines.append(transport)

        def arrived(data: bytes, now: int) -> None:
            self._input("data", key, bytes(data))  # hex: the writer's thread
            on_data(data, now)

        def closed(now: int) -> None:
            self._input("close", key)
            if on_close is not None:
                on_close(now)

        return arrived, closed

    def _line_set(self, key: str) -> Callable[[PeerLine], None]:
        def line_set(line: PeerLine) -> None:
            self._input("settings", key, line.baud, line.stop_bits, line.odd)

        return line_set

    def _sending(self, key: str) -> Callable[[bytes], None]:
        def sent(data: bytes) -> None:
            self.writer.add(["send", self.clock.now, key, bytes(data)])  # hex: the writer's

        return sent

    def listener(self, listener: Listener, on_connect: ConnectCallback) -> ConnectCallback:
        key = self.keys.listener()

        def connected(transport: Transport, now: int) -> None:
            self._input("accept", key)
            on_connect(transport, now)

        return connected

    # --- what the binder tells, and the door's commands -------------------------------

    def bound(self, groups: Sequence[str]) -> None:
        self._input("bind", sorted(groups))

    def watch(self, door: Door) -> None:
        """See every outermost command of ``door`` (a console line, a control call)."""
        if self._unwatch is None:
            self._unwatch = door.watch(self)

    def before(self, command: Command) -> None:
        if self.closed:
            return
        if command.kind == LINE:
            self._input("line", command.name)
        else:
            self._input(command.kind, command.name, list(command.args))

    def after(self, command: Command, answer: object, error: BaseException | None) -> None:
        """The command returned (``ret``) and what it answered; one that raised something
        other than a plant error (Ctrl-C) ends the session: nothing more is written."""
        if self.closed or (error is not None and not isinstance(error, FieldtwinError)):
            return
        label = "console" if command.kind == LINE else command.name
        self._input("ret")
        result = {"error": str(error)} if error is not None else plain_json(answer)
        self.writer.add(["result", self.clock.now, label, result])

    def close(self) -> None:
        """The end record; the file closed (flushed).  Safe to call twice."""
        if self.closed:
            return
        self.closed = True
        if self._unwatch is not None:
            self._unwatch()
            self._unwatch = None
        for transport in self._observed:
            transport.observe_sends(None)
        self._observed.clear()
        for pty in self._lines:
            pty.observe_line(None)
        self._lines.clear()
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
