"""Issue 15 item 2: on a real RTU endpoint a reply leaves when a real line would deliver
its last character (TES 7.2.7): request characters, t3.5, tr, answer delay, reply.

The core (``RtuLine`` with a ``WireTiming``) is checked in simulated time; the glue
(``serve_rtu`` on a pty, ``serve_rtu_over_tcp``) at ``speed=None``, where the runner
jumps to each deadline, so the send instant is read off the simulated clock.
"""

from __future__ import annotations

from fractions import Fraction

import pytest

from fieldtwin.clock import MS, SimClock
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.line import RtuLine
from fieldtwin.modbus.model import Link, ReadWords, Request, WriteWord, WriteWords
from fieldtwin.modbus.pdu import encode_request
from fieldtwin.modbus.timing import (
    TYPICAL_TR_US,
    RtuTiming,
    WireTiming,
    exchange_time_us,
    reply_bytes,
    reply_latency_us,
)
from fieldtwin.runtime.modbus_server import serve_rtu, serve_rtu_over_tcp
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.base import Transport, line_settings
from fieldtwin.transports.pty import open_pty
from fieldtwin.transports.serial import open_serial
from fieldtwin.transports.tcp import connect, listen
from tests.modbus.modbus_fakes import TableDevice

LIMIT = 5_000 * MS
REQUESTS: tuple[Request, ...] = (
    ReadWords(3, 0, 10),
    WriteWord(1, 7),
    WriteWords(0, tuple(range(10))),
)


def rtu(slave: int, request: Request) -> bytes:
    return with_crc(bytes((slave,)) + encode_request(request))


@pytest.mark.parametrize("baud", [1200, 9600, 19200, 38400])
@pytest.mark.parametrize("request_", REQUESTS)
def test_the_reply_leaves_when_the_line_delivers_its_last_character(
    baud: int, request_: Request
) -> None:
    fmt = line_settings(baud, 8, "E", 1)
    timing = RtuTiming.from_format(fmt).relaxed(2 * MS, eager=True, max_lead_us=10**6)
    device = TableDevice(5, delay_us=3 * MS)
    line = RtuLine([device], Link.RS485, timing, wire=WireTiming.from_format(fmt))
    frame = rtu(5, request_)
    line.receive(frame, 1000)
    nq, nr = len(frame), reply_bytes(request_)
    char = Fraction(11 * 1_000_000, baud)
    want = 1000 + round(char * (nq + nr)) + round(char * 7 / 2) + TYPICAL_TR_US + 3 * MS
    assert line.next_deadline() == want
    assert line.poll(want - 1) == []
    (sent,) = line.poll(want)
    assert (sent.at, len(sent.data)) == (want, nr)
    # the formula's share up to the reply's last character: T without Sr and tq
    t = exchange_time_us(11, baud, nq, nr)
    assert abs(want - 1000 - 3 * MS - (t - round(char * 3) - 1500 + round(char / 2))) <= 1


def test_a_uart_carries_the_characters_itself() -> None:
    fmt = line_settings(9600, 8, "E", 1)
    wire = WireTiming.from_format(fmt, carried=True)
    assert wire.reply_at(500, 8, 25, 0) == 500 + round(fmt.char_time * 7 / 2) + TYPICAL_TR_US


def test_without_wire_timing_the_reply_leaves_after_the_answer_delay() -> None:
    fmt = line_settings(38400, 8, "E", 1)
    timing = RtuTiming.from_format(fmt).relaxed(2 * MS, eager=True, max_lead_us=10**6)
    line = RtuLine([TableDevice(5, delay_us=MS)], Link.RS485, timing)
    line.receive(rtu(5, ReadWords(3, 0, 1)), 1000)
    assert line.next_deadline() == 1000 + MS


def _sent_at(runner: Runner, transport: Transport) -> list[int]:
    """Wrap ``send``: the simulated instants the server sends at."""
    times: list[int] = []
    send = transport.send

    def timed(data: bytes) -> None:
        times.append(runner.clock.now)
        send(data)

    transport.send = timed  # type: ignore[method-assign]
    return times


@pytest.mark.parametrize("wire", [True, False])
def test_a_pty_line_is_wire_timed_unless_switched_off(wire: bool) -> None:
    runner = Runner(SimClock(), speed=None)
    fmt = line_settings(19200, 8, "E", 1)
    pty = open_pty(fmt)
    times = _sent_at(runner, pty)
    server = serve_rtu(runner, pty, [TableDevice(3)], Link.RS485, fmt, wire_timing=wire)
    assert pty.peer_path is not None
    peer = open_serial(pty.peer_path, fmt)
    try:
        request = ReadWords(3, 0, 10)
        peer.send(rtu(3, request))
        got = bytearray()
        start = runner.clock.now

        def replied() -> bool:
            got.extend(peer.receive())
            return len(got) >= 25

        assert runner.run_until(replied, LIMIT)
        (sent,) = times
        read_at = sent - (reply_latency_us(fmt, 8, 25) if wire else 0)
        assert start <= read_at <= runner.clock.now  # the request's read instant
    finally:
        peer.close()
        server.close()


def test_rtu_over_tcp_is_wire_timed() -> None:
    runner = Runner(SimClock(), speed=None)
    fmt = line_settings(9600, 8, "E", 1)
    listener = listen("127.0.0.1", 0)
    server = serve_rtu_over_tcp(runner, listener, [TableDevice(3)], fmt)
    client = connect(*listener.address)
    try:
        client.send(rtu(3, WriteWord(0, 9)))
        got = bytearray()
        start = runner.clock.now

        def replied() -> bool:
            client.flush()
            got.extend(client.receive())
            return len(got) >= 8

        assert runner.run_until(replied, LIMIT)
        # at least the wire time of both frames, t3.5 and tr after the request left
        assert runner.clock.now - start >= reply_latency_us(fmt, 8, 8)
    finally:
        client.close()
        server.close()


def test_a_pty_opened_as_a_serial_device_carries_no_baud_rate() -> None:
    pty = open_pty()
    assert pty.peer_path is not None
    port = open_serial(pty.peer_path)
    try:
        assert port.carries_baud is False
    finally:
        port.close()
        pty.close()
