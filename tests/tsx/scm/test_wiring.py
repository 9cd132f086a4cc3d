"""What a channel is wired to: serial ports that follow the configuration, the SCA2 loop
phase (PSR), injected reception faults that outlive a reconfiguration, table limits."""

from __future__ import annotations

import os
import select
import termios
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from fieldtwin.devices.scm.status import lines as status_lines
from fieldtwin.errors import ConfigError
from fieldtwin.facade import inject_fault
from fieldtwin.plant import load_plant
from fieldtwin.tsx.plc import Plc
from tests.tsx.scm.helpers import PLAIN_HD, configure, fault_bits, m, make, ready

CONFIG_7E1_1200 = [0x0721, 0x1200, 0, 0, 0, 0, 0, 0]  # 7 bits, even parity, 1 stop, 1200 baud


@pytest.fixture
def pty_pair() -> Iterator[tuple[int, str]]:
    """A pty whose slave plays a serial device (as /dev/ttyUSB0 would)."""
    master, slave = os.openpty()
    try:
        yield master, os.ttyname(slave)
    finally:
        os.close(master)
        os.close(slave)


def _termios(path: str) -> list[object]:
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    try:
        return list(termios.tcgetattr(fd))
    finally:
        os.close(fd)


def test_serial_endpoint_follows_the_channel_configuration(pty_pair: tuple[int, str]) -> None:
    # SCM 3.2: the UART takes the configured speed and format; a host serial port wired to
    # the channel without explicit settings must be set the same way (on each configuration)
    master, device = pty_pair
    plc = Plc(scan_ms=10, speed=50.0)
    mod = plc.insert("TSX SCM 2011", rack=0, slot=7)
    assert mod.attach(0, f"serial://{device}") == device
    plc.advance(1.05)
    assert configure(plc, 7, 0, CONFIG_7E1_1200).v == 0xFE
    attrs = _termios(device)
    cflag = int(attrs[2])  # type: ignore[call-overload]
    assert attrs[4] == termios.B1200 and attrs[5] == termios.B1200
    # 7E1: some pty drivers refuse a new character size on an open slave; then the status
    # says so (a real serial port takes it)
    seven_even = cflag & termios.CSIZE == termios.CS7 and cflag & termios.PARENB
    assert seven_even or "host port refused" in status_lines(mod)["channel 0"]
    assert not cflag & termios.PARODD and not cflag & termios.CSTOPB
    r = plc.exchange(m=0x0700, c=0x01, send_bytes=b"OK")
    assert r.v == 0 and _read_exactly(master, 2) == b"OK"
    mod.detach(0)


def _read_exactly(fd: int, count: int, limit_s: float = 10.0) -> bytes:
    """``count`` bytes from ``fd``: the characters may reach the pty in separate writes."""
    data = b""
    deadline = time.monotonic() + limit_s
    while len(data) < count and time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], max(0.0, deadline - time.monotonic()))
        if ready:
            data += os.read(fd, count - len(data))
    return data


def test_serial_endpoint_with_explicit_settings_keeps_them(pty_pair: tuple[int, str]) -> None:
    master, device = pty_pair
    plc = Plc(scan_ms=10, speed=50.0)
    mod = plc.insert("TSX SCM 2011", rack=0, slot=7)
    mod.attach(0, f"serial://{device}?baud=19200&parity=N&data=8&stop=1")
    plc.advance(1.05)
    configure(plc, 7, 0, CONFIG_7E1_1200)
    attrs = _termios(device)
    assert attrs[4] == termios.B19200 and int(attrs[2]) & termios.CSIZE == termios.CS8  # type: ignore[call-overload]
    mod.detach(0)


def test_5_1_sca2_psr_inverts_the_loop_receiver() -> None:
    # SCM 5.1 SCA2: PSR 0 = multipoint, 1 = point-to-point; "The state of this bit inverses
    # the current loop reception circuit logic": a PSR that does not match the loop wiring
    # makes the receiver read every level inverted (garbage and format errors)
    plc, mod = make("TSX SCM 2022")
    peer = mod.attach_memory(0)
    mod.set_loop(0, "point-to-point")
    assert configure(plc, 7, 0, PLAIN_HD).v == 0xFE
    tb = plc.start_exchange(m=m(0), c=0x03, send=[0x0002, 2], recv_bytes=4)  # 200 ms
    plc.advance(0.02)
    peer.send(b"ok")  # PSR still 0 (multipoint): the receiver logic is inverted
    plc.advance(0.3)
    assert tb.result is not None and tb.result.data != b"ok"
    assert fault_bits(plc) >> 37 & 1  # a format error shows as the channel's parity fault
    plc.write("O7,0", 1)  # PSR = 1: point-to-point
    plc.advance(0.02)
    assert plc.read("I7,8") == 1  # the input image of PSR
    tb = plc.start_exchange(m=m(0), c=0x04, send=[2], recv_bytes=4)
    plc.advance(0.02)
    peer.send(b"ok")
    plc.advance(0.05)
    assert tb.result is not None and tb.result.data == b"ok"


def test_5_1_sca2_multipoint_loop_reads_with_psr_0() -> None:
    plc, mod = make("TSX SCM 2022")
    peer = mod.attach_memory(1)
    mod.set_loop(1, "multipoint")
    configure(plc, 7, 1, PLAIN_HD)
    tb = plc.start_exchange(m=m(1), c=0x04, send=[2], recv_bytes=4)
    plc.advance(0.02)
    peer.send(b"hi")
    plc.advance(0.05)
    assert tb.result is not None and tb.result.data == b"hi"
    with pytest.raises(ConfigError, match="loop"):
        mod.set_loop(1, "ring")
    plc, mod = make("TSX SCM 2011")
    with pytest.raises(ConfigError, match="SCA2"):
        mod.set_loop(0, "multipoint")


def test_injected_parity_fault_outlives_a_new_configuration() -> None:
    # fault injection (plant `faults = ["parity_ch0"]`) comes before the channel tables;
    # the configuration that follows must not silently drop it
    plc, mod = make()
    peer = mod.attach_memory(0)
    inject_fault(mod, "parity_ch0", True)
    assert configure(plc, 7, 0, PLAIN_HD).v == 0xFE
    tb = plc.start_exchange(m=m(0), c=0x04, send=[1], recv_bytes=2)
    plc.advance(0.02)
    peer.send(b"x")
    plc.advance(0.02)
    assert tb.done and fault_bits(plc) >> 37 & 1
    inject_fault(mod, "parity_ch0", False)
    tb = plc.start_exchange(m=m(0), c=0x04, send=[1], recv_bytes=2)
    plc.advance(0.02)
    peer.send(b"y")
    plc.advance(0.02)
    assert tb.done and not fault_bits(plc) >> 37 & 1


@pytest.mark.parametrize(
    "code,header,chars,ok",
    [(1, 0, 254, True), (1, 0, 255, False), (0, 2, 252, True), (0, 2, 253, False)],
)
def test_amb_scm_23_text_block_limit_includes_the_header(
    code: int, header: int, chars: int, ok: bool
) -> None:
    # SCM 4.5 "TXTi,S ... 1 to 254 maximum" is the Text Block's limit: TXTi,L counts the
    # time-out word too, so request 0 carries at most 252 characters
    plc, mod, peer = ready()
    r = plc.exchange(m=m(0), c=code, send_bytes=b"\0" * header + b"z" * chars)
    assert (r.e, r.s) == ((False, 0) if ok else (True, 2))


def test_4_1_thirty_characters_on_a_47_20() -> None:
    # SCM 4.1 "30 characters in a TSX 47-20"
    plc, mod = make("TSX SCM 2011", slot=3, model="TSX 47-20", code=63)
    peer = mod.attach_memory(0)
    assert configure(plc, 3, 0, PLAIN_HD).v == 0xFE
    assert plc.exchange(m=0x0300, c=0x01, send_bytes=b"a" * 30).v == 0
    assert plc.exchange(m=0x0300, c=0x01, send_bytes=b"a" * 31).s == 2
    assert peer.receive() == b"a" * 30


def test_plant_loop_key(tmp_path: Path) -> None:
    plant = tmp_path / "loop.toml"
    plant.write_text(
        '[[module]]\ntype = "TSX SCM 2012"\nslot = 3\n'
        'channels = [{ channel = 1, loop = "point-to-point" }]\n'
    )
    plc = load_plant(plant).plc
    assert plc is not None
    mod = plc.module(0, 3)
    assert mod.signals[1].rx_inverted  # PSR still 0 after power-up
    assert "loop point-to-point (receiver inverted)" in status_lines(mod)["channel 1"]
    plant.write_text(
        '[[module]]\ntype = "TSX SCM 2012"\nslot = 3\nchannels = [{ channel = 0, loop = "x" }]\n'
    )
    with pytest.raises(ConfigError, match=r"channels\[0\]\.loop"):
        load_plant(plant)


def test_4_5_code_10_incorrect_indirect_addressing() -> None:
    # SCM 4.5 TXTi,S = 10: "incorrect addressing with an indirect Text block"
    plc, mod, peer = ready()
    plc.data[100] = 5000  # beyond the internal words
    r = plc.exchange(m=m(0), c=0x01, indirect=100, length=2)
    assert (r.e, r.s) == (True, 10)
    plc.data[100], plc.data[200] = 200, 0x4241
    assert plc.exchange(m=m(0), c=0x01, indirect=100, length=2).v == 0
    assert peer.receive() == b"AB"
