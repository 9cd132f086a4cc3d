"""SCM 4.1-4.3: half-duplex transmission, reception, transmission/reception; echo, BS, XON/XOFF."""

from __future__ import annotations

import itertools

from fieldtwin.tsx.scm.channel import XOFF, XON
from tests.tsx.scm.helpers import (
    CHAR_US_9600_8N2,
    CONFIG_3_3,
    PLAIN_HD,
    SLOT,
    fault_bits,
    m,
    ready,
)

P1_FAULT_W150 = [0x3150, 0x2020, 0x4146, 0x4C55, 0x2054]  # SCM 4.1 table at W150


def test_4_1_p1_fault_transmission_without_time_out() -> None:
    # SCM 4.1 example: TX2,M = H'0700', C = H'0001', L = 10, table at W150
    plc, mod, peer = ready(words=CONFIG_3_3)
    plc.data[150:155] = P1_FAULT_W150
    r = plc.exchange(m=0x0700, c=0x0001, table=150, length=10, txt=2)
    assert (r.v, r.s, r.e) == (0x0000, 0, False)
    assert peer.receive() == b"P1  FAULT "  # 1st character in the low byte
    times = [t for t, _ in peer.log]
    assert all(b - a == CHAR_US_9600_8N2 for a, b in itertools.pairwise(times))


def test_4_1_transmission_with_time_out_reached_while_xoff() -> None:
    plc, mod, peer = ready(words=[0x0802, 0x9600, 0, 0x0010, 0, 0, 0, 0])  # XON/XOFF (T)
    tb = plc.start_exchange(m=m(0), c=0x00, send_bytes=b"\x01\x00" + b"A" * 40)  # 100 ms
    plc.advance(0.015)
    peer.send(bytes([XOFF]))
    plc.advance(0.3)
    assert tb.result is not None and tb.result.v == 0xFD
    assert fault_bits(plc) >> 35 & 1  # 3rd word bit 3: time-out on WRITE request
    assert len(peer.receive()) < 40


def test_3_2_xon_xoff_pause_and_resume() -> None:
    plc, mod, peer = ready(words=[0x0802, 0x9600, 0, 0x0010, 0, 0, 0, 0])
    tb = plc.start_exchange(m=m(0), c=0x01, send_bytes=b"0123456789" * 3)
    plc.advance(0.0125)  # the request is validated at 10 ms; two characters have left
    peer.send(bytes([XOFF]))
    plc.advance(0.5)
    paused = peer.receive()
    assert 1 <= len(paused) < 30 and not tb.done
    assert plc.read("IW7,1,1") == 1 and plc.read("IW7,1,2") == 1  # running, transmitting
    peer.send(bytes([XON]))
    plc.advance(0.1)
    assert tb.result is not None and tb.result.v == 0
    assert paused + peer.receive() == b"0123456789" * 3


def test_4_1_request_2_ends_at_once_without_report() -> None:
    plc, mod, peer = ready()
    r = plc.exchange(m=m(0), c=0x02, send_bytes=b"X" * 100)
    assert (r.v, r.s) == (0, 0)
    assert plc.read("IW7,1,1") == 1  # still transmitting
    busy = plc.exchange(m=m(0), c=0x01, send_bytes=b"Y")
    assert busy.e and busy.s == 5  # AMB: refused while the channel runs
    plc.advance(0.2)
    assert peer.receive() == b"X" * 100 and plc.read("IW7,1,1") == 0


def test_4_2_reception_with_time_out_reached() -> None:
    plc, mod, peer = ready(words=CONFIG_3_3)
    tb = plc.start_exchange(m=m(0), c=0x03, send=[0x0020, 10], recv_bytes=20)  # 2 s, 10 chars
    plc.advance(0.5)
    peer.send(b"abc")
    plc.advance(1.0)
    assert not tb.done and plc.read("IW7,1,1") == 1 and plc.read("IW7,1,2") == 0
    plc.advance(0.6)
    assert tb.result is not None and (tb.result.v, tb.result.s) == (0xFD, 3)
    assert tb.result.data == b"abc"  # manual-notes: characters received so far
    assert plc.read("IW7,0,7") == 1 and plc.read("IW7,0,4") == 1 and plc.read("I7,S") == 0
    assert fault_bits(plc) >> 34 & 1  # time-out on READ request, channel 0
    plc.advance(0.02)
    assert plc.read("IW7,0,7") == 0  # acknowledged by reading the fault bits


def test_4_2_reception_ends_on_end_character_with_echo() -> None:
    # SCM 3.3 configuration: echo, back-space, ERC-1 = CR not included
    plc, mod, peer = ready(words=CONFIG_3_3)
    tb = plc.start_exchange(m=m(0), c=0x04, send=[20], recv_bytes=20)
    plc.advance(0.02)
    peer.send(b"AB\r")
    plc.advance(0.05)
    assert tb.result is not None and (tb.result.v, tb.result.s, tb.result.data) == (1, 2, b"AB")
    assert peer.receive() == b"AB\r"  # reception echo


def test_4_2_second_end_character_included_and_count() -> None:
    words = [0x0802, 0x9600, 0, 0, 0x0011, 0x0D3B, 0, 0]  # ERC-2 = ';' included
    plc, mod, peer = ready(words=words)
    tb = plc.start_exchange(m=m(0), c=0x04, send=[20], recv_bytes=20)
    plc.advance(0.02)
    peer.send(b"xy;z")
    plc.advance(0.05)
    assert tb.result is not None and (tb.result.v, tb.result.data) == (2, b"xy;")
    assert peer.receive() == b""  # no echo configured
    r = plc.start_exchange(m=m(0), c=0x04, send=[3], recv_bytes=20)
    plc.advance(0.02)
    peer.send(b"123")
    plc.advance(0.05)
    assert r.result is not None and (r.result.v, r.result.data) == (0, b"123")


def test_3_2_back_space_with_echo() -> None:
    plc, mod, peer = ready(words=CONFIG_3_3)
    tb = plc.start_exchange(m=m(0), c=0x04, send=[20], recv_bytes=20)
    plc.advance(0.02)
    peer.send(b"ab\x08c\r")
    plc.advance(0.05)
    assert tb.result is not None and tb.result.data == b"ac"
    assert peer.receive() == b"ab\x08 \x08c\r"  # BS SP BS instead of the BS


def test_amb_scm_17_back_space_without_echo_is_stored() -> None:
    plc, mod, peer = ready(words=[0x0802, 0x9600, 0, 0x0001, 0x1000, 0x0D00, 0, 0])
    tb = plc.start_exchange(m=m(0), c=0x04, send=[20], recv_bytes=20)
    plc.advance(0.02)
    peer.send(b"ab\x08c\r")
    plc.advance(0.05)
    assert tb.result is not None and tb.result.data == b"ab\x08c"


def test_4_2_reception_table_smaller_than_the_count() -> None:
    plc, mod, peer = ready()
    tb = plc.start_exchange(m=m(0), c=0x04, send=[6], recv_bytes=4)
    plc.advance(0.02)
    peer.send(b"123456")
    plc.advance(0.05)
    assert tb.result is not None and (tb.result.e, tb.result.data) == (False, b"1234")


def test_3_2_auto_lf_and_end_of_transmission_character() -> None:
    words = [0x0802, 0x9600, 0, 0x0100, 0, 0, 0x1100, 0x3B00]  # auto-LF, ETC-1 ';' included
    plc, mod, peer = ready(words=words)
    r = plc.exchange(m=m(0), c=0x01, send_bytes=b"A\rB;CD")
    assert r.v == 1 and peer.receive() == b"A\r\nB;"
    words[6] = 0x0011  # ETC-2 ';' included
    words[7] = 0x003B
    plc.exchange(m=m(0), c=0x40, send=words)
    assert plc.exchange(m=m(0), c=0x01, send_bytes=b"XY;Z").v == 2


def _echo_config(timeout_bcd: int) -> list[int]:
    return [0x0802, 0x9600, 0x1000 | timeout_bcd, 0, 0, 0, 0, 0]


def test_3_2_transmission_echo_correct() -> None:
    plc, mod, peer = ready(words=_echo_config(0x002))  # 100 ms echo time-out
    tb = plc.start_exchange(m=m(0), c=0x01, send_bytes=b"OK!")
    for _ in range(30):
        plc.advance(0.005)
        got = peer.receive()
        if got:
            peer.send(got)  # a terminal echoing each character
    assert tb.result is not None and tb.result.v == 0
    assert [b for _, b in peer.log] == list(b"OK!")


def test_3_2_no_echo_after_3_tries() -> None:
    plc, mod, peer = ready(words=_echo_config(0x002))
    r = plc.exchange(m=m(0), c=0x01, send_bytes=b"AB")
    assert r.v == 0xFD
    assert peer.receive() == b"AAAA"  # AMB-SCM-9: sent once, then 3 more tries
    times = [t for t, _ in peer.log]
    assert times[1] - times[0] == 100_000 + CHAR_US_9600_8N2
    assert fault_bits(plc) >> 33 & 1  # 3rd word bit 1: no echo after 3 tries


def test_3_2_wrong_echo_after_3_tries() -> None:
    plc, mod, peer = ready(words=_echo_config(0x010))
    tb = plc.start_exchange(m=m(0), c=0x01, send_bytes=b"A")
    for _ in range(40):
        plc.advance(0.005)
        if peer.receive():
            peer.send(b"?")
    assert tb.result is not None and tb.result.v == 0xFD
    assert fault_bits(plc) >> 32 & 1  # incorrect echo after 3 tries


def test_4_3_transmission_reception_5_and_6() -> None:
    plc, mod, peer = ready(words=CONFIG_3_3)
    tb = plc.start_exchange(m=m(0), c=0x05, send=[0x0010, 3, 0x3F3F], recv_bytes=10)  # "??"
    plc.advance(0.02)
    assert peer.receive() == b"??"
    peer.send(b"yes")
    plc.advance(0.05)
    assert tb.result is not None and (tb.result.v, tb.result.data) == (0, b"yes")
    tb = plc.start_exchange(m=m(0), c=0x06, send=[2, 0x0021], length=3, recv_bytes=10)
    plc.advance(0.02)
    peer.send(b"no")
    plc.advance(0.05)
    assert tb.result is not None and tb.result.data == b"no"
    r = plc.exchange(m=m(0), c=0x05, send=[0x0005, 3, 0x3F3F])  # nobody answers in 0.5 s
    assert r.v == 0xFD and fault_bits(plc) >> 36 & 1  # time-out on WRITE/READ request


def test_4_3_request_7_on_21xy_channel_0_and_refused_on_20xy() -> None:
    plc, mod, peer = ready()
    assert plc.exchange(m=m(0), c=0x07, send=[0, 0, 0x4142]).v == 0xFD  # 20xy: no request 7
    plc, mod, peer = ready("TSX SCM 2111")
    assert plc.exchange(m=m(0), c=0x07, send=[0, 0, 0x4142]).v == 0  # write
    assert peer.receive() == b"BA"
    tb = plc.start_exchange(m=m(0), c=0x07, send=[0x0010, 2], recv_bytes=4)  # read
    plc.advance(0.02)
    peer.send(b"hi")
    plc.advance(0.02)
    assert tb.result is not None and tb.result.data == b"hi"


def test_4_5_bad_tables_report_fd() -> None:
    plc, mod, peer = ready()
    assert plc.exchange(m=m(0), c=0x03, send=[0x00A0, 5]).v == 0xFD  # time not coded in BCD
    assert plc.exchange(m=m(0), c=0x03, send=[0x0010]).v == 0xFD  # L must be 4
    assert plc.exchange(m=m(0), c=0x04, send=[0]).v == 0xFD  # nothing to receive
    assert plc.exchange(m=m(0), c=0x04, send=[255]).v == 0xFD  # more than 254
    assert plc.exchange(m=m(0), c=0x00, send=[0x0010], length=2).v == 0xFD
    assert plc.exchange(m=m(0), c=0x08, send=[1]).v == 0xFD


def test_amb_scm_16_time_out_0_means_none() -> None:
    plc, mod, peer = ready()
    tb = plc.start_exchange(m=m(0), c=0x03, send=[0, 2], recv_bytes=4)
    plc.advance(30)
    assert not tb.done
    peer.send(b"ok")
    plc.advance(0.05)
    assert tb.result is not None and tb.result.v == 0


def test_half_duplex_channel_ignores_characters_between_requests() -> None:
    plc, mod, peer = ready(words=PLAIN_HD)
    peer.send(b"lost")
    plc.advance(0.05)
    tb = plc.start_exchange(m=m(0), c=0x04, send=[2], recv_bytes=4)
    plc.advance(0.05)
    assert not tb.done
    peer.send(b"ok")
    plc.advance(0.05)
    assert tb.result is not None and tb.result.data == b"ok"
    assert SLOT == 7


def test_3_2_echo_of_the_end_character_follows_the_end_of_the_request() -> None:
    # SCM 3.2 reception echo: "Any character received by the module while executing a
    # reception request is immediately sent back"; 4.2: the request ends on the end
    # character.  The CR's echo is still on the line (one character time) when the end
    # of task after it sets TXTi,D: a peer must not expect it when the request has ended.
    plc, mod, peer = ready(words=CONFIG_3_3)
    tb = plc.start_exchange(m=m(0), c=0x04, send=[20], recv_bytes=20)
    task = plc.now + 2 * plc.scan_us  # the request reaches the module at the next task
    cr_received = task - 500  # 0.5 ms before the end of task that follows
    plc.advance((cr_received - 6 * CHAR_US_9600_8N2 - plc.now) / 1e6)
    peer.send(b"hello\r")
    assert plc._run_until(lambda: tb.done, 1_000_000) and plc.now == task
    assert tb.result is not None and (tb.result.v, tb.result.data) == (1, b"hello")
    assert peer.receive() == b"hello"  # the echo of the CR has not left yet
    plc.advance(0.002)
    assert peer.receive() == b"\r"
