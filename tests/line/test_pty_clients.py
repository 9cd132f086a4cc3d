"""Issue 23: four Python Modbus masters open a TES pty at its own 38400 8E1 and read
a word (a real `fieldtwin run`, the masters' own serial code).  Before, opening the
pty with even parity failed with ``termios.error: (22, 'Invalid argument')`` whenever
the pty already held the master's speed (transports/pty.py says why)."""

from __future__ import annotations

import termios
from collections.abc import Callable
from typing import Any

import minimalmodbus
import modbus_tk.defines as cst
import pytest
import serial
from modbus_tk import modbus_rtu
from pymodbus.client import ModbusSerialClient
from umodbus.client.serial import rtu

from fieldtwin.testing.process import RunningPlant

pytestmark = pytest.mark.plant("plants/tes_pty.toml")

WORD = 0x005  # the TES 32EST's inputs 0..15: input 2 is on (0x0004)


def read_minimalmodbus(path: str) -> int:
    instrument = minimalmodbus.Instrument(path, 1, close_port_after_each_call=False)
    port = instrument.serial
    assert port is not None
    if (port.baudrate, port.parity) != (38400, serial.PARITY_EVEN):
        # minimalmodbus opened it at 19200 8N1 (or reuses its cached port): set speed
        # and parity on the closed port, then open once (docs/transports.md)
        port.close()
        port.baudrate, port.parity, port.timeout = 38400, serial.PARITY_EVEN, 2.0
        port.open()
    try:
        return int(instrument.read_register(WORD, functioncode=3))
    finally:
        port.close()


def read_modbus_tk(path: str) -> int:
    port = serial.Serial()  # configured closed: modbus-tk sets its timeouts, then opens
    port.port, port.baudrate, port.parity, port.timeout = path, 38400, serial.PARITY_EVEN, 2.0
    master = modbus_rtu.RtuMaster(port)
    master.set_timeout(2.0)
    try:
        return int(master.execute(1, cst.READ_HOLDING_REGISTERS, WORD, 1)[0])
    finally:
        master.close()


def read_umodbus(path: str) -> int:
    port = serial.Serial(path, 38400, parity=serial.PARITY_EVEN, timeout=2.0)
    try:
        message = rtu.read_holding_registers(slave_id=1, starting_address=WORD, quantity=1)
        return int(rtu.send_message(message, port)[0])
    finally:
        port.close()


def read_pymodbus(path: str) -> int:
    """pymodbus's ``connect()`` opens the port and then sets ``inter_byte_timeout`` on
    it, a change of VMIN only, which glibc refuses on a pty with parity E
    (``test_pymodbus_own_open_at_8e1_fails_on_a_pty``).  The way that works: open the
    port at 38400 8E1 with pyserial, every setting at once, and hand it to the client
    as its ``socket``; ``connect()`` then keeps it (docs/transports.md)."""
    client = ModbusSerialClient(path, baudrate=38400, parity="E", timeout=2, retries=0)
    client.socket = serial.Serial(path, 38400, parity=serial.PARITY_EVEN, timeout=2.0)
    assert client.connect()
    assert client.socket.parity == serial.PARITY_EVEN
    try:
        reply = client.read_holding_registers(WORD, count=1, device_id=1)
        assert not reply.isError(), reply
        return int(reply.registers[0])
    finally:
        client.close()  # type: ignore[no-untyped-call]


READERS: dict[str, Callable[[str], int]] = {
    "minimalmodbus": read_minimalmodbus,
    "modbus-tk": read_modbus_tk,
    "umodbus": read_umodbus,
    "pymodbus": read_pymodbus,
}


def test_four_masters_read_a_tes_pty_at_38400_8e1(running_plant: RunningPlant) -> None:
    path = running_plant.modbus(1).url
    assert "38400 8E1" in running_plant.modbus(1).line
    # each master twice in a row: the second open finds the pty at its own speed
    seen: dict[str, Any] = {}
    for name, read in READERS.items():
        seen[name] = [read(path), read(path)]
    assert seen == {name: [0x0004, 0x0004] for name in READERS}


def test_a_parity_only_change_fails_on_any_linux_pty(running_plant: RunningPlant) -> None:
    """What no twin can change: a pty drops parity (the kernel), and glibc reports a
    ``tcsetattr`` that changed nothing but asked for parity as EINVAL - so a pyserial
    setter on a port already open with parity E fails (docs/transports.md)."""
    port = serial.Serial(running_plant.modbus(1).url, 38400, parity="E", timeout=1.0)
    try:
        with pytest.raises(termios.error, match="Invalid argument"):
            port.inter_byte_timeout = 0.0
    finally:
        port.close()


def test_pymodbus_own_open_at_8e1_fails_on_a_pty(running_plant: RunningPlant) -> None:
    """Why pymodbus needs its port handed over: its own ``connect()`` at parity E fails
    on any Linux pty, with the same EINVAL (not the twin: the pty is parked, and the
    open itself succeeds; it is the ``inter_byte_timeout`` set after it)."""
    client = ModbusSerialClient(
        running_plant.modbus(1).url, baudrate=38400, parity="E", timeout=1, retries=0
    )
    try:
        assert not client.connect()  # pymodbus logs the termios.error and gives up
    finally:
        client.close()  # type: ignore[no-untyped-call]
