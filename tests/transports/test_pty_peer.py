"""The pty backend as its users meet it: a peer opens peer_path with pyserial."""

from __future__ import annotations

import os
import termios
from collections.abc import Iterator

import pytest
import serial

from fieldtwin.transports.base import line_settings
from fieldtwin.transports.pty import PtyTransport, open_pty
from tests.transports.transport_pumping import collect


@pytest.fixture
def pty() -> Iterator[PtyTransport]:
    transport = open_pty()
    yield transport
    transport.close()


def _peer(path: str | None) -> serial.Serial:
    assert path is not None
    return serial.Serial(path, timeout=2)


def test_a_pyserial_peer_reads_what_we_send_and_we_read_what_it_writes(pty: PtyTransport) -> None:
    with _peer(pty.peer_path) as peer:
        pty.send(b"\x01\x03\x00\x00\x00\x02\xc4\x0b")
        assert peer.read(8) == b"\x01\x03\x00\x00\x00\x02\xc4\x0b"
        peer.write(b"\r\nOK\x03")
        assert collect(pty, pty, 5) == b"\r\nOK\x03"


def test_our_reads_never_consume_bytes_meant_for_the_peer(pty: PtyTransport) -> None:
    with _peer(pty.peer_path) as peer:
        pty.send(b"for the peer")
        for _ in range(5):
            assert pty.receive() == b""  # nothing echoed, nothing stolen from the slave
        assert peer.read(12) == b"for the peer"


def test_the_pty_survives_a_peer_closing_and_reopening(pty: PtyTransport) -> None:
    with _peer(pty.peer_path) as first:
        first.write(b"one")
        assert collect(pty, pty, 3) == b"one"
    assert pty.receive() == b""  # no hang-up (EIO) once the peer has gone
    assert not pty.closed
    with _peer(pty.peer_path) as second:
        second.write(b"two")
        assert collect(pty, pty, 3) == b"two"
        pty.send(b"back")
        assert second.read(4) == b"back"


def test_name_and_peer_path(pty: PtyTransport) -> None:
    assert pty.peer_path is not None and os.path.exists(pty.peer_path)
    assert pty.name == f"pty:{pty.peer_path}"
    assert pty.is_real
    assert pty.settings == line_settings()


def test_line_settings_baud_is_visible_to_the_peer() -> None:
    transport = open_pty(line_settings(baud=19200, parity="E"))
    try:
        assert transport.peer_path is not None
        fd = os.open(transport.peer_path, os.O_RDWR | os.O_NOCTTY)
        try:
            attrs = termios.tcgetattr(fd)
        finally:
            os.close(fd)
        assert attrs[4] == attrs[5] == termios.B19200
        assert not attrs[3] & (termios.ECHO | termios.ICANON | termios.ISIG)  # raw
    finally:
        transport.close()


def test_a_non_standard_baud_still_opens() -> None:
    transport = open_pty(line_settings(baud=12345))
    try:
        assert transport.settings.baud == 12345
    finally:
        transport.close()
