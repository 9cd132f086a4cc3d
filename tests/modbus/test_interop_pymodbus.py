"""Interop: the pymodbus 3.16 client (an independent master) against our server glue.

The Runner runs paced x1 in a background thread; every client call has a
timeout and the thread is stopped and joined with a bound.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from dataclasses import dataclass

import pytest
from pymodbus import FramerType
from pymodbus.client import ModbusSerialClient, ModbusTcpClient
from pymodbus.pdu import ExceptionResponse

from fieldtwin.clock import SimClock
from fieldtwin.modbus.model import Counter, Link
from fieldtwin.runtime.modbus_server import serve_rtu, serve_rtu_over_tcp, serve_tcp
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.base import line_settings
from fieldtwin.transports.pty import open_pty
from fieldtwin.transports.tcp import listen
from tests.modbus.modbus_fakes import TableDevice

JOIN_S = 5.0


@dataclass
class Served:
    client: ModbusTcpClient | ModbusSerialClient
    devices: dict[int, TableDevice]
    link: Link


def _run(runner: Runner) -> threading.Thread:
    thread = threading.Thread(target=runner.run_forever, daemon=True)
    thread.start()
    return thread


@pytest.fixture(params=["tcp", "pty", "rtu+tcp"])
def served(request: pytest.FixtureRequest) -> Iterator[Served]:
    runner = Runner(SimClock(), speed=1.0)
    devices = {1: TableDevice(1, status=0xA5), 2: TableDevice(2, delay_us=1500)}
    client: ModbusTcpClient | ModbusSerialClient
    if request.param == "tcp":
        listener = listen("127.0.0.1", 0)
        server = serve_tcp(runner, listener, devices.values())
        client = ModbusTcpClient("127.0.0.1", port=listener.address[1], timeout=2, retries=0)
    elif request.param == "rtu+tcp":
        listener = listen("127.0.0.1", 0)
        server = serve_rtu_over_tcp(runner, listener, devices.values(), line_settings(9600))
        port = listener.address[1]
        client = ModbusTcpClient(
            "127.0.0.1", port=port, framer=FramerType.RTU, timeout=2, retries=0
        )
    else:
        settings = line_settings(38400, 8, "E", 1)
        pty = open_pty(settings)
        server = serve_rtu(runner, pty, devices.values(), Link.RS485, settings)
        assert pty.peer_path is not None
        # Linux ptys refuse PARENB (EINVAL): the peer opens 8N1; the simulated
        # line still times characters as 8E1.
        client = ModbusSerialClient(pty.peer_path, baudrate=38400, timeout=2, retries=0)
    thread = _run(runner)
    try:
        assert client.connect()
        yield Served(client, devices, Link.TCP if request.param == "tcp" else Link.RS485)
    finally:
        client.close()  # type: ignore[no-untyped-call]
        runner.stop()
        thread.join(JOIN_S)
        assert not thread.is_alive()
        server.close()


def test_words_read_and_write(served: Served) -> None:
    c = served.client
    assert c.write_register(10, 0xBEEF, device_id=2).function_code == 6
    assert c.write_registers(20, [1, 2, 3], device_id=2).function_code == 0x10
    rr = c.read_holding_registers(19, count=5, device_id=2)
    assert rr.registers == [19, 1, 2, 3, 23]
    assert c.read_input_registers(10, count=1, device_id=2).registers == [0xBEEF]
    assert served.devices[2].words[10] == 0xBEEF
    assert served.devices[1].words[10] == 10


def test_bits_read_and_write(served: Served) -> None:
    c = served.client
    assert not c.write_coil(3, True, device_id=1).isError()
    assert not c.write_coils(8, [True, False, True, True], device_id=1).isError()
    assert c.read_coils(0, count=12, device_id=1).bits[:12] == [
        *(False, False, False, True, False, False, False, False),
        *(True, False, True, True),
    ]
    assert c.read_discrete_inputs(3, count=1, device_id=1).bits[0] is True


def test_fc07_quick_reading(served: Served) -> None:
    # TES 7.2.6: the low 8 bits of the status word.
    assert served.client.read_exception_status(device_id=1).status == 0xA5


def test_exceptions_come_back_as_pymodbus_exception_responses(served: Served) -> None:
    rr = served.client.read_holding_registers(0x1000, count=2, device_id=1)
    assert rr.isError() and isinstance(rr, ExceptionResponse)
    assert rr.exception_code == 2
    served.devices[2].not_ready = True
    rr = served.client.write_register(0, 1, device_id=2)
    assert isinstance(rr, ExceptionResponse) and rr.exception_code == 4
    assert served.devices[1].counted(Counter.EXCEPTION_REPLIES, served.link) == 1


def test_broadcast_write_reaches_every_device(served: Served) -> None:
    # TES 7.2.6: slave 0 = all slaves, no reply.
    served.client.write_register(30, 0x1234, device_id=0, no_response_expected=True)
    # The next exchange with a device shows the broadcast was executed before it.
    assert served.client.read_holding_registers(30, count=1, device_id=2).registers == [0x1234]
    assert served.devices[1].words[30] == 0x1234
