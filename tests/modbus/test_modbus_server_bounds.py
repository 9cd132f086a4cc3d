"""Issue 10 end to end: a garbage burst never leaves a pty line deaf; churn never grows a server."""

from __future__ import annotations

import contextlib
import socket
import time

import serial

from fieldtwin.clock import MS, SimClock
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.model import Counter, Link, ReadWords
from fieldtwin.modbus.pdu import encode_request
from fieldtwin.modbus.rtu import MAX_FRAME
from fieldtwin.modbus.timing import RtuTiming
from fieldtwin.runtime.modbus_server import serve_rtu, serve_tcp
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.base import line_settings
from fieldtwin.transports.pty import open_pty
from fieldtwin.transports.tcp import listen
from tests.modbus.modbus_fakes import TableDevice

DEADLINE_S = 20.0
BURST = 1024 * 1024  # 1 MiB: about 5 minutes of line time at 38400 8E1


def test_a_burst_at_pty_speed_is_an_overrun_and_the_line_answers_soon_after() -> None:
    runner = Runner(SimClock(), speed=1.0)
    settings = line_settings(38400, 8, "E", 1)
    timing = RtuTiming.from_format(settings)
    pty = open_pty(settings)
    device = TableDevice(1)
    server = serve_rtu(runner, pty, [device], Link.RS485, settings)
    assert pty.peer_path is not None
    # at the line's own speed: a master at another is not read at all (issue 23)
    port = serial.Serial(pty.peer_path, 38400, parity="E", timeout=0, write_timeout=0)
    try:
        garbage, sent = b"\xff" * 4096, 0
        deadline = time.monotonic() + DEADLINE_S
        while sent < BURST and time.monotonic() < deadline:
            with contextlib.suppress(serial.SerialTimeoutException):  # the pty is full
                sent += port.write(garbage) or 0
            runner.advance(1 * MS)
        assert sent >= BURST
        # at most one longest frame of line time, then t3.5 (plus the pty floor)
        runner.advance(MAX_FRAME * timing.char_us + 10 * MS)
        assert device.counted(Counter.WRONG_CHARACTERS) > BURST // 2  # lost to the overrun
        got = bytearray()

        def replied() -> bool:
            got.extend(port.read(64))
            return len(got) >= 7

        port.write(with_crc(b"\x01" + encode_request(ReadWords(3, 2, 1))))
        started = time.monotonic()
        assert runner.run_until(replied, 1000 * MS)
        assert bytes(got) == with_crc(bytes.fromhex("01 03 02 0002"))
        assert time.monotonic() - started < 1.0
    finally:
        port.close()
        server.close()


def test_connect_close_churn_never_grows_the_server() -> None:
    runner = Runner(SimClock(), speed=None)
    listener = listen("127.0.0.1", 0)
    server = serve_tcp(runner, listener, [TableDevice(1)])
    host, port = listener.address
    try:
        for _ in range(5):
            clients = [socket.create_connection((host, port), timeout=5) for _ in range(40)]
            assert runner.run_until(lambda: len(server.pumps) == 40, 2000 * MS)
            for client in clients:
                client.close()
            assert runner.run_until(lambda: not server.pumps, 2000 * MS)
        assert listener.live == 0 and runner.watched == 1  # only the listener is left
    finally:
        server.close()
