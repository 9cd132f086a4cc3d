"""Issue 20 item 7 through the Modbus server: a fresh master is served at the limit.

The server tells its listener whether a connection is in the middle of a
request (a reply still due); the longest-idle connection that is not is hung up
for the new master, and the first eviction is reported once.  Real loopback
sockets, an in-process runner; every wait is bounded.
"""

from __future__ import annotations

import socket
import struct
from collections.abc import Iterator

import pytest

from fieldtwin.clock import MS, S, SimClock
from fieldtwin.runtime.modbus_server import ModbusServer, serve_rtu_over_tcp, serve_tcp
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.base import line_settings
from fieldtwin.transports.tcp import TcpListener, listen
from tests.modbus.modbus_fakes import TableDevice

LIMIT_US = 2000 * MS  # simulated; at most about as long on the wall (no pacing)


class Master:
    """A raw Modbus TCP master: FC03 of word 0 of unit 1, answers collected as they come."""

    def __init__(self, address: tuple[str, int]) -> None:
        self.sock = socket.create_connection(address, timeout=5)
        self.sock.setblocking(False)
        self.got = bytearray()
        self.ended = False
        self.transaction = 0

    def ask(self) -> None:
        self.transaction += 1
        self.sock.sendall(struct.pack(">HHHBBHH", self.transaction, 0, 6, 1, 3, 0, 1))

    def answered(self) -> bool:
        """True once an answer to the last request is in (reads what has arrived)."""
        self._read()
        return len(self.got) >= 11 * self.transaction

    def hung_up(self) -> bool:
        self._read()
        return self.ended

    def _read(self) -> None:
        try:
            data = self.sock.recv(4096)
        except BlockingIOError:
            return
        if not data:
            self.ended = True
        self.got += data

    def close(self) -> None:
        self.sock.close()


@pytest.fixture
def masters() -> Iterator[list[Master]]:
    made: list[Master] = []
    yield made
    for master in made:
        master.close()


def _server(
    device: TableDevice, limit: int, reports: list[str]
) -> tuple[Runner, TcpListener, ModbusServer]:
    runner = Runner(SimClock(), speed=None, report=reports.append)
    listener = listen("127.0.0.1", 0, max_connections=limit)
    return runner, listener, serve_tcp(runner, listener, [device])


def _connect(runner: Runner, server: ModbusServer, masters: list[Master], want: int) -> Master:
    master = Master(server._listener.address)  # type: ignore[union-attr]
    masters.append(master)
    assert runner.run_until(lambda: len(server.pumps) == want, LIMIT_US)
    return master


def test_a_new_master_at_the_limit_is_served_and_the_longest_idle_one_goes(
    masters: list[Master],
) -> None:
    reports: list[str] = []
    runner, listener, server = _server(TableDevice(1), 2, reports)
    try:
        first = _connect(runner, server, masters, 1)
        second = _connect(runner, server, masters, 2)
        first.ask()  # the first master polls: the second one is now the longest idle
        assert runner.run_until(first.answered, LIMIT_US)
        third = _connect(runner, server, masters, 2)
        third.ask()
        assert runner.run_until(third.answered, LIMIT_US)
        assert runner.run_until(second.hung_up, LIMIT_US)  # with a FIN, not a reset
        first.ask()
        assert runner.run_until(first.answered, LIMIT_US)  # still served
        assert listener.evicted == server.evicted == 1 and listener.live == 2
        fourth = _connect(runner, server, masters, 2)  # the third one is the idlest now
        assert runner.run_until(third.hung_up, LIMIT_US)
        assert not first.hung_up()
        fourth.ask()
        assert runner.run_until(fourth.answered, LIMIT_US)
        assert server.evicted == 2
        assert len(reports) == 1  # said once
        assert "2 connections open (the limit)" in reports[0] and server.where in reports[0]
    finally:
        server.close()


def test_a_master_whose_answer_is_due_is_never_hung_up(masters: list[Master]) -> None:
    device = TableDevice(1, delay_us=3600 * S)  # the answer leaves in an hour (simulated)
    runner, listener, server = _server(device, 2, [])
    try:
        waiting = _connect(runner, server, masters, 1)
        waiting.ask()
        assert runner.run_until(lambda: bool(device.log), LIMIT_US)
        idle = _connect(runner, server, masters, 2)
        _connect(runner, server, masters, 2)  # takes the idle one's place, not the waiting one's
        assert runner.run_until(idle.hung_up, LIMIT_US)
        assert not waiting.hung_up() and listener.evicted == 1
        assert runner.run_until(waiting.answered, 3601 * S)  # and it gets its answer
    finally:
        server.close()


def test_when_every_master_waits_for_an_answer_the_new_one_is_refused(
    masters: list[Master],
) -> None:
    device = TableDevice(1, delay_us=3600 * S)
    runner, listener, server = _server(device, 1, [])
    try:
        waiting = _connect(runner, server, masters, 1)
        waiting.ask()
        assert runner.run_until(lambda: bool(device.log), LIMIT_US)
        masters.append(Master(listener.address))
        assert runner.run_until(lambda: listener.refused == 1, LIMIT_US)
        assert listener.evicted == 0 and not waiting.hung_up()
    finally:
        server.close()


def test_rtu_over_tcp_makes_room_the_same_way(masters: list[Master]) -> None:
    runner = Runner(SimClock(), speed=None, report=[].append)
    listener = listen("127.0.0.1", 0, max_connections=1)
    server = serve_rtu_over_tcp(runner, listener, [TableDevice(1)], line_settings(19200, 8, "E", 1))
    try:
        first = _connect(runner, server, masters, 1)
        _connect(runner, server, masters, 1)
        assert runner.run_until(first.hung_up, LIMIT_US)
        assert server.evicted == 1
    finally:
        server.close()
