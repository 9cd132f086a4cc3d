"""Server glue on the Runner: memory and pty RTU lines, Modbus TCP, RTU over TCP."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import serial

from fieldtwin.clock import MS, SimClock
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.mbap import encode_mbap
from fieldtwin.modbus.model import Counter, Link, ReadWords, Request, WriteWord
from fieldtwin.modbus.pdu import encode_request
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.runtime.modbus_server import serve_rtu, serve_rtu_over_tcp, serve_tcp
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.base import Transport, line_settings
from fieldtwin.transports.memory import memory_pair
from fieldtwin.transports.pty import open_pty
from fieldtwin.transports.tcp import TcpTransport, connect, listen
from tests.modbus.modbus_fakes import TableDevice

LINE = line_settings(38400, 8, "E", 1)
LIMIT = 2_000 * MS  # every run is bounded


def rtu(slave: int, request: Request) -> bytes:
    return with_crc(bytes((slave,)) + encode_request(request))


class Reader:
    """Collects what a master end receives, for runner predicates."""

    def __init__(self, transport: Transport) -> None:
        self.transport = transport
        self.got = bytearray()

    def has(self, size: int) -> bool:
        if isinstance(self.transport, TcpTransport):
            self.transport.flush()
        self.got += self.transport.receive()
        return len(self.got) >= size


@pytest.fixture
def runner() -> Iterator[Runner]:
    yield Runner(SimClock(), speed=None)


def test_rtu_line_on_memory_replies_after_frame_end_and_answer_delay(runner: Runner) -> None:
    ours, master = memory_pair()
    device = TableDevice(1, delay_us=1500)
    server = serve_rtu(runner, ours, [device, TableDevice(2)], Link.RS485, LINE)
    assert server.describe() == "listening: modbus-rtu memory slaves 1,2 (38400 8E1)"
    master.send(rtu(1, WriteWord(1, 5)))
    reader = Reader(master)
    assert runner.run_until(lambda: reader.has(8), LIMIT)
    assert bytes(reader.got) == rtu(1, WriteWord(1, 5))  # TES 7.2.3: the reply echoes
    timing = RtuTiming.from_format(LINE)
    assert runner.clock.now == 8 * timing.char_us + timing.t35_us + 1500
    assert device.words[1] == 5
    server.close()
    assert ours.closed and server.connections == 0


def test_rtu_line_on_memory_counts_a_crc_error_and_stays_silent(runner: Runner) -> None:
    ours, master = memory_pair()
    device = TableDevice(1)
    serve_rtu(runner, ours, [device], Link.RS232, LINE)
    master.send(b"\x01\x03\x00\x00\x00\x01\x00\x00")
    reader = Reader(master)
    assert not runner.run_until(lambda: reader.has(1), 50 * MS)
    assert device.counted(Counter.CRC_ERRORS, Link.RS232) == 1


def test_modbus_tcp_serves_several_connections_with_partial_frames(runner: Runner) -> None:
    listener = listen("127.0.0.1", 0)
    one, two = TableDevice(1), TableDevice(2)
    server = serve_tcp(runner, listener, [one, two])
    host, port = listener.address
    assert server.describe() == f"listening: modbus-tcp tcp://{host}:{port} slaves 1,2"
    a, b = connect(host, port), connect(host, port)
    try:
        frame_a = encode_mbap(10, 1, encode_request(ReadWords(3, 5, 1)))
        frame_b = encode_mbap(20, 2, encode_request(WriteWord(5, 77)))
        a.send(frame_a[:4])
        b.send(frame_b + frame_b[:3])
        reader_a, reader_b = Reader(a), Reader(b)
        assert runner.run_until(lambda: reader_b.has(12), LIMIT)
        a.send(frame_a[4:])
        b.send(frame_b[3:])
        assert runner.run_until(lambda: reader_a.has(11) and reader_b.has(24), LIMIT)
        assert bytes(reader_a.got) == bytes.fromhex("000a 0000 0005 01 03 02 0005")
        assert bytes(reader_b.got) == frame_b * 2
        assert server.connections == 2 and two.words[5] == 77
    finally:
        a.close()
        b.close()
        server.close()


def test_modbus_tcp_closes_a_connection_with_a_broken_stream(runner: Runner) -> None:
    listener = listen("127.0.0.1", 0)
    server = serve_tcp(runner, listener, [TableDevice(1)])
    client = connect(*listener.address)
    try:
        client.send(bytes.fromhex("0001 0000 0000 01"))
        assert runner.run_until(lambda: server.connections == 1, LIMIT)
        assert runner.run_until(lambda: server.connections == 0, LIMIT)
    finally:
        client.close()
        server.close()


def test_rtu_over_tcp_cuts_frames_by_length(runner: Runner) -> None:
    listener = listen("127.0.0.1", 0)
    device = TableDevice(3)
    server = serve_rtu_over_tcp(runner, listener, [device], LINE)
    host, port = listener.address
    assert server.describe() == (
        f"listening: modbus-rtu-over-tcp rtu+tcp://{host}:{port} slaves 3 (38400 8E1)"
    )
    client = connect(host, port)
    try:
        first, second = rtu(3, WriteWord(0, 9)), rtu(3, ReadWords(3, 0, 1))
        client.send(first + second[:3])
        reader = Reader(client)
        assert runner.run_until(lambda: reader.has(8), LIMIT)
        client.send(second[3:])
        assert runner.run_until(lambda: reader.has(15), LIMIT)
        assert bytes(reader.got) == first + with_crc(bytes.fromhex("03 03 02 0009"))
    finally:
        client.close()
        server.close()


def test_rtu_line_on_a_pty_answers_a_serial_peer() -> None:
    runner = Runner(SimClock(), speed=1.0)
    settings = line_settings(9600, 8, "E", 1)
    pty = open_pty(settings)
    server = serve_rtu(runner, pty, [TableDevice(3), TableDevice(4)], Link.RS485, settings)
    assert server.describe() == f"listening: modbus-rtu pty {pty.peer_path} slaves 3,4 (9600 8E1)"
    port = serial.Serial(pty.peer_path, timeout=0)
    try:
        got = bytearray()

        def replied() -> bool:
            got.extend(port.read(64))
            return len(got) >= 14

        # Two requests back to back in one write: both answered, in order.
        port.write(rtu(4, ReadWords(3, 1, 1)) + rtu(3, ReadWords(3, 2, 1)))
        assert runner.run_until(replied, LIMIT)
        assert bytes(got) == with_crc(bytes.fromhex("04 03 02 0001")) + with_crc(
            bytes.fromhex("03 03 02 0002")
        )
    finally:
        port.close()
        server.close()
