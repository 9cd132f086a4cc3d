"""Issue 15: an RTU line counts its line-wide counters once per frame (a shared tally),
and every TES reads exactly what counting frame by frame in each TES gave.

Two identical lines of three TES hear the same random traffic (frames to each
slave and to others, broadcasts, bad CRCs, fragments, master writes of the
counter words, power cycles): one line shares a tally, the other is built on a
``SlaveSet`` without one (each TES counts every frame itself, as before).
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from fieldtwin.clock import MS
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.line import RtuLine
from fieldtwin.modbus.model import Link, ReadWords, Request, WriteWord, WriteWords
from fieldtwin.modbus.pdu import encode_request
from fieldtwin.modbus.slave import SlaveSet
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.tes import Tes
from fieldtwin.transports.base import line_settings

TIMING = RtuTiming.from_format(line_settings(38400, 8, "E", 1))
COUNTERS = 0x017  # §6.2.3.2: 7 words per link from 017h (TES 32EST, RS-485)


def _frame(slave: int, request: Request, bad_crc: bool) -> bytes:
    frame = bytearray(with_crc(bytes((slave,)) + encode_request(request)))
    if bad_crc:
        frame[-1] ^= 0xFF
    return bytes(frame)


_request = st.one_of(
    st.builds(ReadWords, st.just(3), st.integers(0, 0x20), st.integers(1, 8)),
    st.builds(WriteWord, st.integers(COUNTERS, COUNTERS + 6), st.integers(0, 0xFFFF)),
    st.builds(
        WriteWords,
        st.just(COUNTERS),
        st.lists(st.integers(0xFFF0, 0xFFFF), min_size=7, max_size=7).map(tuple),
    ),
)
_step = st.one_of(
    st.tuples(st.just("frame"), st.integers(0, 4), _request, st.booleans()),
    st.tuples(st.just("junk"), st.binary(min_size=1, max_size=3)),
    st.tuples(st.just("power"), st.integers(0, 2)),
)


def _line(shared: bool) -> tuple[RtuLine, list[Tes]]:
    devices = [Tes("TES 32EST", n) for n in (1, 2, 3)]
    slaves = devices if shared else SlaveSet(devices, Link.RS485)
    return RtuLine(slaves, Link.RS485, TIMING), devices


def _counters(devices: list[Tes]) -> list[tuple[int, ...]]:
    out = []
    for tes in devices:
        regs = [tes.registers.table[a] for a in range(COUNTERS, COUNTERS + 7)]
        out.append(tuple(tes.registers.peek(r, 0) for r in regs))
    return out


@settings(max_examples=80, deadline=None)
@given(st.lists(_step, max_size=30))
def test_a_shared_tally_counts_as_every_tes_counting(steps: list[tuple]) -> None:  # type: ignore[type-arg]
    lines = [_line(True), _line(False)]
    now = 0
    for step in steps:
        now += 20 * MS
        for line, devices in lines:
            if step[0] == "frame":
                line.receive(_frame(step[1], step[2], step[3]), now)
            elif step[0] == "junk":
                line.receive(step[1], now)
            else:
                devices[step[1]].power_cycle()
            line.poll(now + 10 * MS)
        assert _counters(lines[0][1]) == _counters(lines[1][1]), step
    assert lines[0][0].slaves._tally is not None and lines[1][0].slaves._tally is None


def test_one_frame_costs_one_count_whatever_the_number_of_slaves() -> None:
    devices = [Tes("TES 32EST", n) for n in range(1, 248)]
    line = RtuLine(devices, Link.RS485, TIMING)
    calls = 0
    for tes in devices:
        count = tes.count

        def counting(link: Link, counter: object, at: int, count=count) -> None:  # type: ignore[no-untyped-def]
            nonlocal calls
            calls += 1
            count(link, counter, at)  # type: ignore[arg-type]

        tes.count = counting  # type: ignore[method-assign]
    line.receive(_frame(200, ReadWords(3, 0, 1), False), 0)
    line.poll(10 * MS)
    assert calls == 1  # the addressed TES counts its reply; the good frame is one tally
    assert all(tes.read(0x01C) == 1 for tes in devices)  # 01Ch received frames without errors
