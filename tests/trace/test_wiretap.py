"""The wiretap's decoders on the simulated clock: fields, outcomes, RTU CRC, pairing."""

from __future__ import annotations

from dataclasses import dataclass, field

from fieldtwin.clock import MS, SimClock
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.model import Counter, Link, Request, Result
from fieldtwin.modbus.slave import SlaveSet
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.runtime.events import Event, EventBus
from fieldtwin.runtime.wiretap import CharTap, Wiretap, function_name, request_fields
from fieldtwin.transports.base import line_settings


@dataclass
class Faults:
    no_answer: bool = False
    queued: list[object] = field(default_factory=list)

    def pending(self, link: Link) -> object | None:
        return self.queued[0] if self.queued else None


@dataclass
class FakeTes:
    slave: int
    name: str
    powered: bool = True
    line_faults: Faults = field(default_factory=Faults)
    delay_us: int = 0

    def execute(self, request: Request, link: Link, now: int, broadcast: bool) -> Result:
        return None

    def count(self, link: Link, counter: Counter, now: int) -> None:
        pass

    def answer_delay(self, link: Link) -> int:
        return self.delay_us


@dataclass(frozen=True)
class BadCrc:
    value: str = "bad_crc"


def tap(link: Link = Link.TCP, rtu: bool = False) -> tuple[Wiretap, list[Event], list[FakeTes]]:
    bus = EventBus()
    sub = bus.subscribe()
    devices = [FakeTes(1, "A"), FakeTes(2, "B")]
    timing = RtuTiming.from_format(line_settings(9600, 8, "E", 1)) if rtu else None
    kind = "rtu" if rtu else "tcp"
    wiretap = Wiretap(bus, f"{kind}://x", kind, SlaveSet(devices, link), timing, "tcp://1.2.3.4:5")
    events: list[Event] = []
    sub._notify = lambda: events.extend(sub.take())
    return wiretap, events, devices


def mbap(transaction: int, unit: int, pdu: bytes) -> bytes:
    head = transaction.to_bytes(2, "big") + b"\x00\x00" + (len(pdu) + 1).to_bytes(2, "big")
    return head + bytes((unit,)) + pdu


def test_request_fields_of_every_function() -> None:
    assert request_fields(bytes.fromhex("0300100002")) == {
        "function": 3,
        "function_name": "read_holding_registers",
        "address": 16,
        "count": 2,
    }
    assert request_fields(bytes.fromhex("100001000204000a000b"))["count"] == 2
    assert request_fields(bytes.fromhex("050003ff00"))["count"] == 1
    rejected = request_fields(bytes.fromhex("2b"))
    assert rejected["rejected"] == 1 and rejected["function"] == 0x2B
    assert function_name(0x83) == "read_holding_registers_exception"


def test_tcp_frames_say_who_answers_and_why_not() -> None:
    wiretap, events, (a, b) = tap()
    stream = wiretap.stream("10.0.0.1:999")
    b.line_faults.no_answer = True
    # two frames in one chunk, the second cut in the middle, then its rest
    data = mbap(7, 1, bytes.fromhex("0300000002")) + mbap(8, 2, bytes.fromhex("0400000001"))
    stream.inbound(data[:-3], 10)
    stream.inbound(data[-3:], 20)
    assert [(e.t_us, e.data["transaction"], e.data["tes"]) for e in events] == [
        (10, 7, {"A": "answers", "B": "not_addressed"}),
        (20, 8, {"A": "not_addressed", "B": "no_answer"}),
    ]
    assert events[0].device == "tcp://x 1" and events[0].kind == "modbus"
    assert (
        events[0].data["listen"] == "tcp://1.2.3.4:5" and events[0].data["conn"] == "10.0.0.1:999"
    )
    stream.outbound(mbap(7, 1, bytes.fromhex("03040001000a")), 30)
    reply = events[-1].data
    assert (reply["dir"], reply["from"], reply["address"], reply["count"]) == ("out", "A", 0, 2)
    stream.outbound(mbap(9, 9, bytes.fromhex("830b")), 40)
    assert events[-1].data["exception"] == 11 and events[-1].data["from"] == "server"
    assert events[-1].device == "tcp://x"


def test_powered_off_late_and_broadcast() -> None:
    wiretap, events, (a, b) = tap()
    stream = wiretap.stream("c")
    a.powered, b.delay_us = False, 250 * MS
    stream.inbound(mbap(1, 1, bytes.fromhex("0300000001")), 0)
    stream.inbound(mbap(2, 2, bytes.fromhex("0300000001")), 0)
    stream.inbound(mbap(3, 0, bytes.fromhex("0600010005")), 0)
    stream.inbound(mbap(4, 0, bytes.fromhex("0300010005")), 0)
    assert [e.data["tes"] for e in events] == [
        {"A": "powered_off", "B": "not_addressed"},
        {"A": "not_addressed", "B": "answers after 250 ms"},
        {"A": "powered_off", "B": "broadcast"},
        {"A": "powered_off", "B": "broadcast_ignored"},
    ]


def test_a_stream_that_cannot_be_framed_is_reported_and_resynchronised() -> None:
    wiretap, events, _ = tap()
    stream = wiretap.stream("c")
    stream.inbound(bytes(7), 0)  # MBAP length 0
    assert "outside 2..254" in str(events[0].data["error"])
    stream.inbound(mbap(1, 1, bytes.fromhex("0300000001")), 5)
    assert events[-1].data["function"] == 3


def test_rtu_frames_crc_faults_and_line_faults_on_the_simulated_clock() -> None:
    wiretap, events, (a, b) = tap(Link.RS485, rtu=True)
    stream = wiretap.stream("pty /dev/pts/9")
    timing = wiretap.timing
    assert timing is not None
    frame = with_crc(bytes.fromhex("010300000002"))
    stream.inbound(frame, 0)
    stream.poll(timing.t35_us + len(frame) * timing.char_us)
    assert events[-1].data["crc"] == "good" and events[-1].data["tes"]["A"] == "answers"
    t = 100 * MS
    broken = bytearray(with_crc(bytes.fromhex("020300000002")))
    broken[-1] ^= 0xFF
    stream.inbound(bytes(broken), t)
    stream.poll(t + 100 * MS)
    assert events[-1].data["crc"] == "bad" and events[-1].data["fault"] == "crc_errors"
    b.line_faults.queued.append(BadCrc())
    t = 300 * MS
    stream.inbound(with_crc(bytes.fromhex("020300000002")), t)
    stream.poll(t + 100 * MS)
    assert events[-1].data["tes"] == {"A": "not_addressed", "B": "bad_crc"}
    stream.outbound(with_crc(bytes.fromhex("0103040001000a")), t + 200 * MS)
    out = events[-1].data
    assert (out["dir"], out["crc"], out["from"], out["count"]) == ("out", "good", "A", 2)


def test_scm_characters_come_in_blocks() -> None:
    clock = SimClock()
    bus = EventBus()
    sub = bus.subscribe()
    chars = CharTap(bus, clock, "7", 0, "pty")
    for i, c in enumerate(b"HELLO"):
        chars.chars("out", bytes((c,)), i * MS)
    chars.chars("in", b"ok", 2 * MS)
    assert len(sub) == 0  # nothing until the line has been quiet
    clock.advance(20 * MS)
    got = sub.take()
    assert [(e.t_us, e.data["dir"], e.data["text"], e.data["count"]) for e in got] == [
        (2 * MS, "in", "ok", 2),
        (0, "out", "HELLO", 5),
    ]
    assert got[0].kind == "serial" and got[0].device == "7"


def test_a_scm_tcp_channel_remembers_a_bounded_number_of_peers() -> None:
    from fieldtwin.facade.host import _connected
    from fieldtwin.tsx.scm.endpoints import MAX_CONNECTION_NAMES, Port

    class Peer:
        def __init__(self, name: str) -> None:
            self.name, self.closed = name, False

        def close(self) -> None:
            self.closed = True

    class Pacer:
        def attach(self, transport: object, on_data: object) -> None:
            pass

        def detach(self, transport: object) -> None:
            pass

    port = Port("tcp://127.0.0.1:0", None, runner=Pacer())  # type: ignore[arg-type]
    for i in range(1000):  # a peer that reconnects all day long
        _connected(port, Peer(f"peer {i}"))
    assert len(port.connections) == MAX_CONNECTION_NAMES
    assert port.connections[-1] == "peer 999"


def test_a_write_the_tes_answered_is_a_register_event_a_refused_one_is_not() -> None:
    wiretap, events, (a, b) = tap()
    stream = wiretap.stream("c")
    stream.inbound(mbap(1, 2, bytes.fromhex("100010000204000a000b")), 5)  # FC16 2 words
    stream.outbound(mbap(1, 2, bytes.fromhex("1000100002")), 9)
    registers = [e for e in events if e.kind == "register"]
    assert [
        (r.t_us, r.device, r.data["tes"], r.data["address"], r.data["values"]) for r in registers
    ] == [(9, "tcp://x 2", "B", 16, [10, 11])]
    stream.inbound(mbap(2, 1, bytes.fromhex("0600050007")), 20)  # FC06 refused by the TES
    stream.outbound(mbap(2, 1, bytes.fromhex("8602")), 21)
    stream.inbound(mbap(3, 1, bytes.fromhex("0300000001")), 30)  # a read writes nothing
    stream.outbound(mbap(3, 1, bytes.fromhex("03020000")), 31)
    stream.inbound(mbap(4, 1, bytes.fromhex("050003ff00")), 40)  # FC05 a bit
    stream.outbound(mbap(4, 1, bytes.fromhex("050003ff00")), 41)
    registers = [e for e in events if e.kind == "register"]
    assert [(r.data["table"], r.data["address"], r.data["values"]) for r in registers] == [
        ("words", 16, [10, 11]),
        ("bits", 3, [1]),
    ]


def test_an_rtu_broadcast_write_is_a_register_event_of_every_tes_that_executed_it() -> None:
    wiretap, events, (a, b) = tap(Link.RS485, rtu=True)
    timing = wiretap.timing
    assert timing is not None
    a.powered = False
    stream = wiretap.stream("pty")
    frame = with_crc(bytes.fromhex("000600010005"))
    stream.inbound(frame, 0)
    stream.poll(timing.t35_us + len(frame) * timing.char_us)
    registers = [e for e in events if e.kind == "register"]
    assert [(r.device, r.data["tes"], r.data["values"]) for r in registers] == [
        ("rtu://x 2", "B", [5])
    ]
