"""Issue 15 item 2: when the serial peer of an RTU line closes, a paced run keeps its pace."""

from __future__ import annotations

from fieldtwin.clock import SimClock
from fieldtwin.modbus.model import Link
from fieldtwin.runtime.modbus_server import serve_rtu
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.base import line_settings
from fieldtwin.transports.pty import open_pty
from fieldtwin.transports.serial import open_serial
from tests.modbus.modbus_fakes import TableDevice


def test_a_run_stays_paced_after_the_serial_peer_hangs_up() -> None:
    runner = Runner(SimClock(), speed=1000.0)
    fmt = line_settings(38400, 8, "E", 1)
    peer = open_pty(fmt)  # plays the master's end; the twin opens its path as a serial port
    assert peer.peer_path is not None
    port = open_serial(peer.peer_path, fmt)
    server = serve_rtu(runner, port, [TableDevice(3)], Link.RS485, fmt)
    try:
        assert runner.paced
        peer.close()  # the master side goes: the twin's serial port reads a hang-up
        runner.advance(50_000)  # bounded: 50 ms simulated at x1000
        assert port.closed
        assert runner.paced  # still paced: simulated time keeps following the wall
    finally:
        server.close()
    assert not runner.paced  # nothing real left once the server is closed
