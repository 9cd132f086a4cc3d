"""A multi-drop RTU line: dispatch by slave number, broadcast, exceptions, counters."""

from __future__ import annotations

import enum

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.errors import ConfigError
from fieldtwin.modbus.crc import crc_ok, with_crc
from fieldtwin.modbus.line import RtuLine, Wiring
from fieldtwin.modbus.model import (
    NO_REPLY,
    Counter,
    ExceptionCode,
    Link,
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    Request,
    Result,
    WriteWord,
    WriteWords,
)
from fieldtwin.modbus.pdu import decode_response, encode_request
from fieldtwin.modbus.slave import Transmission
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.transports.base import line_settings
from tests.modbus.modbus_fakes import TableDevice
from tests.modbus.modbus_strategies import small_requests

TIMING = RtuTiming.from_format(line_settings(38400, 8, "E", 1))
CT, T35 = TIMING.char_us, TIMING.t35_us
FAR = 10**9


def rtu(slave: int, request: Request) -> bytes:
    return with_crc(bytes((slave,)) + encode_request(request))


def make_line(*devices: TableDevice, wiring: Wiring = Wiring.DOUBLE_PAIR) -> RtuLine:
    return RtuLine(devices, Link.RS485, TIMING, wiring)


def exchange(line: RtuLine, frame: bytes, at: int = 0) -> list[Transmission]:
    line.receive(frame, at)
    out: list[Transmission] = []
    while (deadline := line.next_deadline()) is not None:
        out += line.poll(deadline)
    return out


def end_of(frame: bytes, at: int = 0) -> int:
    """When the framer sees the frame complete: its last character plus t3.5."""
    return at + len(frame) * CT + T35


def test_only_the_addressed_slave_answers_after_its_delay() -> None:
    one, two = TableDevice(1, delay_us=1500), TableDevice(2)
    line = make_line(one, two)
    request = rtu(1, ReadWords(3, 4, 2))
    [reply] = exchange(line, request)
    assert reply.data == with_crc(bytes.fromhex("01 03 04 0004 0005"))
    assert reply.at == end_of(request) + 1500
    assert [r for r, _, _ in one.log] == [ReadWords(3, 4, 2)] and two.log == []


def test_section_6_2_3_2_counters_for_own_and_other_frames() -> None:
    one, two = TableDevice(1), TableDevice(2)
    line = make_line(one, two)
    exchange(line, rtu(1, WriteWord(0, 7)))
    # Every slave counts the good frame; only the addressee counts it executed.
    assert one.counted(Counter.GOOD_FRAMES) == two.counted(Counter.GOOD_FRAMES) == 1
    assert one.counted(Counter.FRAMES_EXECUTED) == 1
    assert two.counted(Counter.FRAMES_EXECUTED) == 0


def test_frame_for_an_absent_slave_gets_no_reply() -> None:
    one = TableDevice(1)
    line = make_line(one)
    assert exchange(line, rtu(9, ReadWords(3, 0, 1))) == []
    assert one.log == [] and one.counted(Counter.GOOD_FRAMES) == 1
    assert sum(one.counters.values()) == 1


def test_section_7_2_6_broadcast_write_is_executed_by_all_without_reply() -> None:
    one, two = TableDevice(1), TableDevice(2)
    line = make_line(one, two)
    assert exchange(line, rtu(0, WriteWords(10, (1, 2)))) == []
    for device in (one, two):
        assert device.words[10:12] == [1, 2]
        assert device.log[0][1] is True  # executed as a broadcast
        assert device.counted(Counter.FRAMES_EXECUTED) == 1


@pytest.mark.parametrize("request_", [ReadWords(3, 0, 1), ReadBits(1, 0, 8), ReadExceptionStatus()])
def test_amb_tes_29_broadcast_reads_are_ignored(request_: Request) -> None:
    one = TableDevice(1)
    assert exchange(make_line(one), rtu(0, request_)) == []
    assert one.log == [] and one.counted(Counter.FRAMES_EXECUTED) == 0


def test_broadcast_write_refused_by_a_device_is_silent() -> None:
    one = TableDevice(1)
    assert exchange(make_line(one), rtu(0, WriteWord(0x1000, 1))) == []
    assert one.counted(Counter.EXCEPTION_REPLIES) == 0


def test_section_7_exception_code_2_for_a_bad_address() -> None:
    one = TableDevice(1)
    [reply] = exchange(make_line(one), rtu(1, ReadWords(3, 0x1000, 1)))
    assert reply.data == with_crc(b"\x01\x83\x02")
    assert one.counted(Counter.EXCEPTION_REPLIES) == 1
    assert one.counted(Counter.FRAMES_EXECUTED) == 0


def test_section_7_exception_code_1_for_an_unknown_function() -> None:
    one = TableDevice(1)
    [reply] = exchange(make_line(one), with_crc(b"\x01\x2b\x0e\x01\x00"))
    assert reply.data == with_crc(b"\x01\xab\x01")
    assert one.log == [] and one.counted(Counter.EXCEPTION_REPLIES) == 1


def test_section_7_code_4_not_ready_is_counted_apart() -> None:
    one = TableDevice(1, not_ready=True)
    [reply] = exchange(make_line(one), rtu(1, ReadWords(3, 0, 1)))
    assert reply.data == with_crc(b"\x01\x83\x04")
    assert one.counted(Counter.NOT_READY_REPLIES) == 1
    assert one.counted(Counter.EXCEPTION_REPLIES) == 0


def test_section_7_2_6_quick_reading() -> None:
    one = TableDevice(1, status=0x81)
    [reply] = exchange(make_line(one), rtu(1, ReadExceptionStatus()))
    assert reply.data == bytes.fromhex("01 07 81 e2 50")


def test_line_faults_are_counted_by_every_slave() -> None:
    one, two = TableDevice(1), TableDevice(2)
    line = make_line(one, two)
    bad = bytearray(rtu(1, ReadWords(3, 0, 1)))
    bad[3] ^= 0xFF
    assert exchange(line, bytes(bad)) == []
    assert exchange(line, b"\x01\x02", at=FAR // 4) == []
    for device in (one, two):
        assert device.counted(Counter.CRC_ERRORS) == 1
        assert device.counted(Counter.WRONG_CHARACTERS) == 2
    assert one.log == []


def test_single_pair_bus_counts_other_slaves_replies_as_not_analysed() -> None:
    # TES 6.2.3.2 01Dh: "bus single pair: idem or replies sent by other slaves".
    one, two, three = TableDevice(1), TableDevice(2), TableDevice(3)
    line = make_line(one, two, three, wiring=Wiring.SINGLE_PAIR)
    exchange(line, rtu(1, ReadWords(3, 0, 1)))
    assert [d.counted(Counter.NO_SILENCE) for d in (one, two, three)] == [0, 1, 1]


def test_double_pair_bus_does_not_hear_replies() -> None:
    one, two = TableDevice(1), TableDevice(2)
    exchange(make_line(one, two), rtu(1, ReadWords(3, 0, 1)))
    assert two.counted(Counter.NO_SILENCE) == 0


def test_replies_of_slaves_with_different_delays_leave_in_time_order() -> None:
    slow, fast = TableDevice(1, delay_us=50_000), TableDevice(2, delay_us=0)
    line = make_line(slow, fast)
    line.receive(rtu(1, ReadWords(3, 0, 1)) + rtu(2, ReadWords(3, 0, 1)), 0)
    out: list[Transmission] = []
    while (deadline := line.next_deadline()) is not None:
        out += line.poll(deadline)
    assert [t.data[0] for t in out] == [2, 1]
    assert out[0].at < out[1].at


@pytest.mark.parametrize(
    ("numbers", "message"),
    [((1, 1), "used twice"), ((0,), "allowed 1"), ((248,), "allowed 1"), ((), "no slave")],
)
def test_bad_slave_numbers_are_config_errors(numbers: tuple[int, ...], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        make_line(*(TableDevice(n) for n in numbers))


@given(st.lists(st.tuples(st.integers(0, 4), small_requests), min_size=1, max_size=8))
def test_multi_drop_answers_exactly_the_present_slaves_in_order(
    items: list[tuple[int, Request]],
) -> None:
    devices = {1: TableDevice(1, delay_us=1500), 3: TableDevice(3, delay_us=1500)}
    line = make_line(*devices.values())
    out: list[Transmission] = []
    at = 0
    for slave, request in items:
        frame = rtu(slave, request)
        out += exchange(line, frame, at)
        at = end_of(frame, at) + 10_000
    expected = [(s, r) for s, r in items if s in devices]
    assert [t.data[0] for t in out] == [s for s, _ in expected]
    for transmission, (_, request) in zip(out, expected, strict=True):
        assert crc_ok(transmission.data)
        result = decode_response(request, transmission.data[1:-2])
        assert result is None or not isinstance(result, ExceptionCode) or result == 2
    for device in devices.values():
        assert device.counted(Counter.GOOD_FRAMES) == len(items)


class SilentDevice(TableDevice):
    """Stays silent (as an unpowered TES would) for reads."""

    def execute(self, request: Request, link: Link, now: int, broadcast: bool) -> Result:
        super().execute(request, link, now, broadcast)
        return NO_REPLY


def test_a_device_answering_no_reply_stays_silent() -> None:
    device = SilentDevice(1)
    assert exchange(make_line(device), rtu(1, ReadWords(3, 0, 1))) == []
    assert device.counted(Counter.FRAMES_EXECUTED) == 0
    assert device.counted(Counter.EXCEPTION_REPLIES) == 0


class TwoNumbers(TableDevice):
    """A device with one slave number per link (TES 3.1.3 / 3.1.4)."""

    def slave_for(self, link: Link) -> int:
        return self.slave + 10 if link is Link.RS232 else self.slave


def test_slave_number_per_link() -> None:
    device = TwoNumbers(1)
    line = RtuLine([device], Link.RS232, TIMING)
    assert exchange(line, rtu(1, ReadWords(3, 0, 1))) == []
    [reply] = exchange(line, rtu(11, ReadWords(3, 0, 1)), at=FAR // 4)
    assert reply.data[0] == 11


class Faulty(TableDevice):
    def __init__(self, slave: int, faults: list[str]) -> None:
        super().__init__(slave)
        self.faults = [_Fault(f) for f in faults]

    def take_line_fault(self, link: Link) -> enum.Enum | None:
        return self.faults.pop(0) if self.faults else None


class _Fault(enum.Enum):
    BAD_CRC = "bad_crc"
    BROKEN_CHARACTER = "broken_character"


def test_injected_line_faults_corrupt_the_next_frames_to_the_device() -> None:
    faulty, other = Faulty(1, ["bad_crc", "broken_character"]), TableDevice(2)
    line = make_line(faulty, other)
    request = rtu(1, ReadWords(3, 0, 1))
    assert exchange(line, request) == []
    assert exchange(line, request, at=FAR // 4) == []
    assert len(exchange(line, request, at=FAR // 2)) == 1
    for device in (faulty, other):
        assert device.counted(Counter.CRC_ERRORS) == 1
        assert device.counted(Counter.WRONG_CHARACTERS) == 1
        assert device.counted(Counter.GOOD_FRAMES) == 1
