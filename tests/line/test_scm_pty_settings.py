"""Issue 23 item 1 for the SCM: a master on a channel's pty at another speed than the
channel's configuration (SCM 3.2) is received as the module's UART samples it - the
format fault of SCM 6.3; at the channel's own speed, no fault.  A real pty, pyserial."""

from __future__ import annotations

import serial

from fieldtwin.tsx.plc import Plc
from tests.tsx.scm.helpers import fault_bits, m

FULL_DUPLEX_9600_8N2 = [0x1802, 0x9600, 0, 0, 0, 0, 0, 0, 0]
FORMAT_FAULT_CH1 = 46  # SCM 6.3 (21xy): 3rd word bit E, format fault in reception


def plc_with_a_pty_channel() -> tuple[Plc, str]:
    plc = Plc(model="TSX 87", scan_ms=10)
    mod = plc.insert("TSX SCM 2111", rack=0, slot=7)
    plc.advance(1.05)  # the initial self-test
    path = mod.attach(1, "pty")
    plc.exchange(m=m(1), c=0x40, send=FULL_DUPLEX_9600_8N2)
    return plc, path


def send_at(plc: Plc, path: str, baud: int) -> int:
    with serial.Serial(path, baud, stopbits=2, timeout=1.0) as port:
        port.write(b"\x00")
        port.flush()
        plc.advance(0.1)  # paced by the wall (a real endpoint): the byte is read and received
    return fault_bits(plc) >> FORMAT_FAULT_CH1 & 1


def test_a_master_at_half_the_speed_makes_a_format_fault() -> None:
    plc, path = plc_with_a_pty_channel()
    assert send_at(plc, path, 4800) == 1  # stop bits sampled at 0


def test_a_master_at_the_channels_speed_makes_none() -> None:
    plc, path = plc_with_a_pty_channel()
    assert send_at(plc, path, 9600) == 0
