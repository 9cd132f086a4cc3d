"""Issue 10 item 4: a peer faster than the line loses characters; memory stays bounded.

docs/manual-notes.md "SCM overrun": at most RX_BACKLOG characters wait for the wire;
what a peer writes beyond that is lost as in a UART overrun, reported on a 21's
full-duplex channel 1 as the "overload fault in reception" (SCM 6.3, 3rd word bit F).
"""

from __future__ import annotations

import contextlib
import os

import serial

from fieldtwin.devices.scm.status import lines as status_lines
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.scm.line import ECHO_BACKLOG, RX_BACKLOG
from tests.tsx.scm.helpers import CHAR_US_9600_8N2, PLAIN_HD, fault_bits, m, ready
from tests.tsx.scm.test_fullduplex import SLOT, fd, read

OVERLOAD_CH1 = 32 + 8 + 7  # SCM 6.3 (TSX SCM 21) 3rd word bit F
CH0_FAULTS = 0xFF << 32  # SCM 6.3 3rd word, channel 0 byte


def test_a_burst_beyond_the_backlog_is_lost_on_a_half_duplex_channel() -> None:
    plc, mod, peer = ready(words=PLAIN_HD)
    tb = plc.start_exchange(m=m(0), c=0x04, send=[254], recv_bytes=254)
    plc.advance(0.02)
    peer.send(b"x" * 100_000)  # 100 000 characters at once: far faster than 9600 baud
    line = mod.lines[0]
    assert line.backlog == RX_BACKLOG and line.overruns == 100_000 - RX_BACKLOG
    plc.advance(RX_BACKLOG * CHAR_US_9600_8N2 / 1e6 + 0.02)
    assert line.backlog == 0
    assert tb.result is not None and (tb.result.v, tb.result.data) == (0, b"x" * 254)
    # SCM 6.3 (20 layout): no fault bit names an overrun; the characters are only lost
    assert fault_bits(plc) & CH0_FAULTS == 0
    assert "99744 characters lost (overrun)" in status_lines(mod)["channel 0"]


def test_an_overrun_on_full_duplex_raises_the_overload_fault() -> None:
    plc, mod, peer = fd()
    rx = read(plc, 200)
    plc.advance(0.02)
    peer.send(b"a" * 100)
    peer.send(b"b" * 200)  # 156 still fit behind the first 100, 44 are lost
    assert mod.lines[1].overruns == 44
    plc.advance(0.5)
    assert rx.result is not None and rx.result.data == b"a" * 100 + b"b" * 100
    assert plc.read("IW2,4") == 56 and plc.read("IW2,2,0") == 0  # the buffer never overflowed
    r = plc.exchange(m=(SLOT << 8) | 0x63, c=0x47, recv_bytes=6, txt=31)
    assert int.from_bytes(r.data, "little") >> OVERLOAD_CH1 & 1


def test_a_pty_flood_keeps_the_receiver_bounded() -> None:
    plc = Plc(scan_ms=10, speed=20.0)
    mod = plc.insert("TSX SCM 2111", rack=0, slot=SLOT)
    path = mod.attach(1, "pty")
    with serial.Serial(path, 9600, timeout=0) as port:
        plc.advance(1.05)
        assert plc.exchange(m=(SLOT << 8) | 1, c=0x40, send=[0x1802, 0x9600] + [0] * 7).v == 0xFE
        fd_ = port.fileno()
        os.set_blocking(fd_, False)
        written = 0
        for _ in range(40):  # bounded: 40 rounds of 10 ms simulated
            with contextlib.suppress(BlockingIOError):  # the pty is full: write later
                written += os.write(fd_, os.urandom(4096))
            plc.advance(0.01)
            assert mod.lines[1].backlog <= RX_BACKLOG
        line = mod.lines[1]
        assert written > 8 * RX_BACKLOG and line.overruns > 0
        assert len(mod.channels[1].buffer) <= 254 and len(mod.channels[1].ends) <= 255
    mod.detach(1)
    r = plc.exchange(m=(SLOT << 8) | 0x63, c=0x47, recv_bytes=6, txt=31)
    assert int.from_bytes(r.data, "little") >> OVERLOAD_CH1 & 1


def test_an_echo_that_cannot_keep_up_is_cut() -> None:
    # rx echo + back-space: each "a BS" pair is echoed as 4 characters (a, BS SP BS)
    plc, mod, peer = fd([0x1802, 0x9600, 0, 0x1001, 0, 0, 0, 0, 0])
    line = mod.lines[1]
    for _ in range(12):  # 12 bursts at the line's own pace: none is lost on the way in
        peer.send(b"a\x08" * (RX_BACKLOG // 2))
        plc.advance(RX_BACKLOG * CHAR_US_9600_8N2 / 1e6)
        assert line.queued <= ECHO_BACKLOG
    assert line.overruns == 0 and line.echo_dropped > 0
    plc.advance(0.05)
    assert plc.read("IW2,4") == 0  # every "a" was deleted by its back-space


def test_end_characters_in_a_row_keep_one_message_end() -> None:
    # ERC-1 = CR, not included: a flood of CRs ends no new message after the first
    plc, mod, peer = fd([0x1802, 0x9600, 0, 0, 0x1000, 0x0D00, 0, 0, 0])
    peer.send(b"\r" * 200)
    plc.advance(0.5)
    assert mod.channels[1].ends == [(0, 1)]
    rx = read(plc, 10)
    plc.advance(0.03)
    assert rx.result is not None and (rx.result.v, rx.result.data) == (1, b"")
