"""The serial backend (pyserial, timeout=0) on a pty slave, which is a serial device."""

from __future__ import annotations

import pytest
import serial as pyserial

from fieldtwin.errors import TransportError
from fieldtwin.transports.base import LineSettings, line_settings
from fieldtwin.transports.pty import open_pty
from fieldtwin.transports.serial import open_serial
from tests.transports.transport_pumping import collect


def test_opening_a_missing_device_names_it() -> None:
    with pytest.raises(TransportError, match="/dev/no-such-tty"):
        open_serial("/dev/no-such-tty", line_settings())


@pytest.mark.parametrize(
    ("settings", "parity"),
    [
        (line_settings(9600, 8, "N", 1), pyserial.PARITY_NONE),
        (line_settings(19200, 7, "E", 2), pyserial.PARITY_EVEN),
        (line_settings(38400, 8, "O", 1), pyserial.PARITY_ODD),
    ],
)
def test_line_settings_reach_the_port(settings: LineSettings, parity: str) -> None:
    master = open_pty()
    assert master.peer_path is not None
    port = open_serial(master.peer_path, settings)
    try:
        # a Linux pty ignores character size and parity bits: ask pyserial what it set
        assert port.port.baudrate == settings.baud
        assert port.port.bytesize == settings.data_bits
        assert port.port.parity == parity
        assert port.port.stopbits == settings.stop_bits
        assert port.port.timeout == 0
        assert port.name == f"serial://{master.peer_path}"
        assert port.settings == settings
    finally:
        port.close()
        master.close()


def test_default_settings_are_9600_8n1() -> None:
    master = open_pty()
    assert master.peer_path is not None
    port = open_serial(master.peer_path)
    try:
        assert port.settings == line_settings(9600, 8, "N", 1)
        port.send(b"abc")
        assert collect(master, port, 3) == b"abc"
    finally:
        port.close()
        master.close()
