"""End to end: a peer opens the channel's pty with pyserial (or TCP), as a real one would."""

from __future__ import annotations

import socket
import time
from collections.abc import Iterator

import pytest
import serial

from fieldtwin.devices.scm.status import lines as status_lines
from fieldtwin.tsx.plc import Plc
from tests.tsx.scm.helpers import CONFIG_3_3, CONFIG_4_6

FAST = 20.0  # speed factor where the point is not the timing


def _plc(ref: str, speed: float) -> tuple[Plc, object]:
    plc = Plc(scan_ms=10, speed=speed)
    return plc, plc.insert(ref, rack=0, slot=7)


def _read(port: serial.Serial, count: int) -> bytes:
    port.timeout = 2.0
    return bytes(port.read(count))


def _waiting(sock: socket.socket) -> int:
    """Bytes the peer socket could read now (without reading them)."""
    try:
        return len(sock.recv(64, socket.MSG_PEEK | socket.MSG_DONTWAIT))
    except BlockingIOError:
        return 0


@pytest.fixture
def hd() -> Iterator[tuple[Plc, object, serial.Serial]]:
    plc, mod = _plc("TSX SCM 2011", FAST)
    path = mod.attach(0, "pty")  # type: ignore[attr-defined]
    assert path.startswith("/dev/") and path in status_lines(mod)["channel 0"]  # type: ignore[attr-defined]
    with serial.Serial(path, 9600, timeout=0) as port:
        plc.advance(1.05)
        assert plc.exchange(m=0x0700, c=0x40, send=CONFIG_3_3).v == 0xFE
        yield plc, mod, port
    mod.detach(0)  # type: ignore[attr-defined]


# 0.0225: read at once, the CR is received 0.6 ms before an end of task (the race)
@pytest.mark.parametrize("lead_s", [0.02, 0.0225])
def test_pty_reception_with_end_character_and_echo(
    hd: tuple[Plc, object, serial.Serial], lead_s: float
) -> None:
    plc, mod, port = hd
    tb = plc.start_exchange(m=0x0700, c=0x03, send=[0x0050, 20], recv_bytes=20)  # 5 s
    plc.advance(lead_s)
    port.write(b"hello\r")
    assert plc._run_until(lambda: tb.done, 5_000_000)
    assert tb.result is not None and (tb.result.v, tb.result.data) == (1, b"hello")
    # The request ends when the CR is received; its echo leaves one character time later
    # (test_3_2_echo_of_the_end_character_follows_the_end_of_the_request): keep the
    # simulation running until the whole echo is at the peer, never read it from a
    # stopped simulation (the race of issue 10 item 14).
    assert plc._run_until(lambda: port.in_waiting >= 6, 5_000_000)
    assert _read(port, 6) == b"hello\r"  # the reception echo reaches the peer


def test_pty_transmission_and_time_out(hd: tuple[Plc, object, serial.Serial]) -> None:
    plc, mod, port = hd
    r = plc.exchange(m=0x0700, c=0x01, send_bytes=b"P1  FAULT ")
    assert r.v == 0 and _read(port, 10) == b"P1  FAULT "
    r = plc.exchange(m=0x0700, c=0x03, send=[0x0005, 4], recv_bytes=4)  # 0.5 s, nobody types
    assert r.v == 0xFD


def test_pty_paces_simulated_time_to_the_wall_clock() -> None:
    plc, mod = _plc("TSX SCM 2011", 1.0)
    plc.advance(1.05)  # not wired yet: the self-test runs at full speed
    plc.exchange(m=0x0700, c=0x40, send=CONFIG_3_3)
    path = mod.attach(0, "pty")  # type: ignore[attr-defined]
    with serial.Serial(path, 9600, timeout=0):
        start = time.monotonic()
        r = plc.exchange(m=0x0700, c=0x03, send=[0x0003, 4], recv_bytes=4)  # 0.3 s time-out
        assert r.v == 0xFD and time.monotonic() - start >= 0.28
    mod.detach(0)  # type: ignore[attr-defined]


def test_pty_full_duplex_read_and_write_together() -> None:
    plc, mod = _plc("TSX SCM 2111", FAST)
    path = mod.attach(1, "pty")  # type: ignore[attr-defined]
    with serial.Serial(path, 9600, timeout=0) as port:
        plc.advance(1.05)
        assert plc.exchange(m=0x0701, c=0x40, send=CONFIG_4_6).v == 0xFE
        rx = plc.start_exchange(m=0x0701, c=0x07, send=[0x0050, 5], recv_bytes=10, txt=0)
        tx = plc.exchange(m=0x0701, c=0x07, send_bytes=b"\0\0\0\0READY", txt=7)
        assert tx.v == 0 and _read(port, 5) == b"READY" and not rx.done
        port.write(b"12345")
        assert plc._run_until(lambda: rx.done, 5_000_000)
        assert rx.result is not None and rx.result.data == b"12345"
    mod.detach(1)  # type: ignore[attr-defined]


def test_tcp_loopback_endpoint() -> None:
    plc, mod = _plc("TSX SCM 2011", FAST)
    url = mod.attach(0, "tcp://127.0.0.1:0")  # type: ignore[attr-defined]
    host, port = url.removeprefix("tcp://").rsplit(":", 1)
    with socket.create_connection((host, int(port)), timeout=2) as sock:
        plc.advance(1.05)
        plc.exchange(m=0x0700, c=0x40, send=CONFIG_3_3)
        tb = plc.start_exchange(m=0x0700, c=0x04, send=[10], recv_bytes=10)
        plc.advance(0.05)
        sock.sendall(b"tcp\r")
        assert plc._run_until(lambda: tb.done, 5_000_000)
        assert tb.result is not None and tb.result.data == b"tcp"
        assert plc._run_until(lambda: _waiting(sock) >= 4, 5_000_000)  # the CR's echo too
        sock.settimeout(2)
        got = b""
        while len(got) < 4:
            got += sock.recv(16)
        assert got == b"tcp\r"
    mod.detach(0)  # type: ignore[attr-defined]
