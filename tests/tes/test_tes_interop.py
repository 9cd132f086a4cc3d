"""Black box: the pymodbus client against TES served by start_tes_endpoints.

The Runner runs paced x1 in a background thread; every client call has a
timeout and the thread is stopped and joined with a bound.
"""

from __future__ import annotations

import re
import threading
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from pymodbus.client import ModbusSerialClient, ModbusTcpClient
from pymodbus.pdu import ExceptionResponse

from fieldtwin.clock import SimClock
from fieldtwin.facade.tes import build_tes, start_tes_endpoints
from fieldtwin.modbus.model import Link
from fieldtwin.runtime.runner import Runner

JOIN_S = 5.0


class Served:
    def __init__(self, tables: list[dict[str, Any]]) -> None:
        self.runner = Runner(SimClock(), speed=1.0)
        self.tes = build_tes(
            tables, self.runner.clock, "plant.toml", __import__("pathlib").Path(".")
        )
        self.servers = start_tes_endpoints(self.tes, tables, self.runner)
        self.lines = [s.describe() for s in self.servers]
        self.thread = threading.Thread(target=self.runner.run_forever, daemon=True)
        self.thread.start()

    def close(self) -> None:
        self.runner.stop()
        self.thread.join(JOIN_S)
        assert not self.thread.is_alive()
        for server in self.servers:
            server.close()


def _poll(read: Callable[[], object], expected: object, tries: int = 200) -> bool:
    """Bounded: the paced clock needs a few ms for the first acquisition."""
    return any(read() == expected for _ in range(tries))


@pytest.fixture
def tcp() -> Iterator[tuple[Served, ModbusTcpClient]]:
    served = Served(
        [
            {
                "model": "TES 32EST",
                "slave": 1,
                "endpoint": "tcp://127.0.0.1:0",
                "inputs": {"3": True},
            },
            {
                "model": "TES 8EA",
                "slave": 3,
                "endpoint": "tcp://127.0.0.1:0",
                "inputs": {"a0": 5.0},
            },
        ]
    )
    port = int(re.search(r"tcp://127\.0\.0\.1:(\d+)", served.lines[0]).group(1))  # type: ignore[union-attr]
    client = ModbusTcpClient("127.0.0.1", port=port, timeout=2, retries=0)
    try:
        assert client.connect()  # type: ignore[no-untyped-call]
        yield served, client
    finally:
        client.close()  # type: ignore[no-untyped-call]
        served.close()


def test_describe_lines(tcp: tuple[Served, ModbusTcpClient]) -> None:
    served, _ = tcp
    assert len(served.lines) == 1
    assert served.lines[0].startswith("listening: modbus-tcp tcp://127.0.0.1:")
    assert "slaves 1,3" in served.lines[0]


def test_tcp_reads_writes_and_exceptions(tcp: tuple[Served, ModbusTcpClient]) -> None:
    _, c = tcp
    r = c.read_holding_registers(0x005, count=1, device_id=1)
    assert not r.isError() and r.registers == [0x0008]  # direct input 3
    assert not c.write_register(0x00D, 0x0005, device_id=1).isError()
    r = c.read_holding_registers(0x007, count=1, device_id=1)
    assert r.registers == [0x0005]
    r = c.read_coils(0x0070, count=4, device_id=1)  # §7.1.2 bits of word 007h
    assert r.bits[:4] == [True, False, True, False]
    assert _poll(lambda: c.read_input_registers(0x003, count=1, device_id=3).registers, [512])
    r = c.read_holding_registers(0x44F, count=1, device_id=3)
    assert isinstance(r, ExceptionResponse) and r.exception_code == 2
    r = c.write_register(0x003, 1, device_id=3)
    assert isinstance(r, ExceptionResponse) and r.exception_code == 2


def test_tcp_fc07_quick_status(tcp: tuple[Served, ModbusTcpClient]) -> None:
    _, c = tcp
    for _ in range(200):  # bounded: wait for the 5 ms input filter on the paced clock
        if c.read_holding_registers(0x003, count=1, device_id=1).registers == [0x0008]:
            break
    r = c.read_exception_status(device_id=1)
    assert not r.isError() and r.status == 0x09  # power on + memorized change waiting


def test_one_pty_line_shared_by_two_tes() -> None:
    served = Served(
        [
            {"model": "TES 32ST", "slave": 5, "endpoint": "pty"},
            {"model": "TES 4EA", "slave": 6, "endpoint": "pty", "inputs": {"a1": 10.0}},
        ]
    )
    try:
        assert len(served.lines) == 1 and "slaves 5,6" in served.lines[0]
        path = re.search(r"pty (\S+)", served.lines[0]).group(1)  # type: ignore[union-attr]
        client = ModbusSerialClient(path, baudrate=38400, timeout=2, retries=0)
        try:
            assert client.connect()
            assert not client.write_registers(0x005, [0x00F0, 0x0001], device_id=5).isError()
            r = client.read_holding_registers(0x001, count=2, device_id=5)
            assert r.registers == [0x00F0, 0x0001]
            read = client.read_holding_registers
            assert _poll(lambda: read(0x004, count=1, device_id=6).registers, [1023])
            r = client.read_holding_registers(0x048, count=2, device_id=6)
            assert not r.isError()  # RS-485 counters of the 4EA
            r = client.read_holding_registers(0x01C, count=1, device_id=5)  # RS-485 good frames
            assert r.registers[0] >= 3  # every frame on the line is counted by every TES
        finally:
            client.close()  # type: ignore[no-untyped-call]
    finally:
        served.close()


def test_a_tcp_gateway_on_the_rs232_port() -> None:
    """`link = "rs232"` on tcp://: the RS-232 number and counters (§3.1.4, §6.3.5)."""
    served = Served(
        [{"model": "TES 32ST", "slave": 9, "endpoint": "tcp://127.0.0.1:0", "link": "rs232"}]
    )
    try:
        assert "slaves 9" in served.lines[0]
        (tes,) = served.tes
        assert tes.slave_for(Link.RS485) == 1
        port = int(re.search(r"tcp://127\.0\.0\.1:(\d+)", served.lines[0]).group(1))  # type: ignore[union-attr]
        client = ModbusTcpClient("127.0.0.1", port=port, timeout=2, retries=0)
        try:
            assert client.connect()  # type: ignore[no-untyped-call]
            r = client.read_holding_registers(0x017, count=14, device_id=9)
            assert r.registers[:7] == [0] * 7  # RS-485 counters untouched
            assert r.registers[7 + 5] == 1  # RS-232 good frames: this request
        finally:
            client.close()  # type: ignore[no-untyped-call]
    finally:
        served.close()
