"""SCM 4.4 / 4.6 / 5.2: channel 1 of a 21xy in full-duplex."""

from __future__ import annotations

from typing import Any

import pytest

from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.scm import MemoryPeer
from fieldtwin.tsx.scm.channel import XOFF, XON
from tests.tsx.scm.helpers import CONFIG_4_6, make

SLOT = 2  # SCM 4.6: module at address 02
M1 = 0x0201


def fd(words: list[int] | None = None) -> tuple[Plc, Any, MemoryPeer]:
    plc, mod = make("TSX SCM 2111", SLOT)
    peer = mod.attach_memory(1)
    # SCM 4.6: TXT1 sends the configuration CW48..CW56 (L = 18)
    plc.data[48:57] = words or CONFIG_4_6
    r = plc.exchange(m=M1, c=0x40, table=48, length=18, txt=1)
    assert (r.v, r.s) == (0xFE, 0)
    return plc, mod, peer


def read(plc: Plc, count: int, timeout_bcd: int = 0, capacity: int = 254) -> Any:
    # SCM 4.6 SR7: W1130 = time-out, W1131 = count, TXT0 receives at W1000
    plc.data[1130:1132] = [timeout_bcd, count]
    return plc.start_exchange(
        m=M1, c=0x07, table=1130, length=4, recv_bytes=capacity, txt=0, recv_table=1000
    )


def write(plc: Plc, text: bytes) -> Any:
    # SCM 4.6 SR5: W2510 = [0, 0, characters], TXT7,L = 4 + W111
    from fieldtwin.words import bytes_to_words

    plc.data[2510:2512] = [0, 0]
    words = bytes_to_words(text)
    plc.data[2512 : 2512 + len(words)] = words
    return plc.start_exchange(m=M1, c=0x07, table=2510, length=4 + len(text), txt=7)


def test_4_6_full_duplex_example() -> None:
    plc, mod, peer = fd()
    rx = read(plc, 5, 0x0100)  # 5 bytes, 10 s time-out
    plc.advance(0.02)
    assert plc.read("IW2,1,9") == 1  # reception running
    tx = write(plc, b"HELLO OPERATOR")  # a write on the same channel while the read waits
    plc.advance(0.03)
    assert tx.result is not None and (tx.result.v, tx.result.s) == (0, 0)
    assert peer.receive() == b"HELLO OPERATOR" and not rx.done
    peer.send(b"12345")
    plc.advance(0.03)
    assert rx.result is not None and (rx.result.v, rx.result.s) == (0, 5)
    assert rx.result.data == b"12345"  # 1st character in the low byte
    assert plc.data[1000:1003] == [0x3231, 0x3433, 0x0035]  # TXT0's reception table W1000
    rx = read(plc, 5, 0x0100)
    plc.advance(9.9)
    assert not rx.done
    plc.advance(0.2)
    assert rx.result is not None and rx.result.v == 253  # SR7: "Time-out? IF [TXT0,V=253]"


def test_text_block_reset_cancels_only_its_own_side() -> None:
    # SCM 4.5 code 1: the read's Text Block is reset while a write runs on the same channel
    plc, mod, peer = fd()
    rx = read(plc, 5, 0x0100)
    plc.advance(0.02)
    tx = write(plc, b"HELLO OPERATOR HELLO OPERATOR")
    plc.advance(0.012)
    plc.reset_text_block(0)
    assert rx.result is not None and rx.result.e and rx.result.s == 1
    plc.advance(0.05)
    assert tx.result is not None and not tx.result.e and tx.result.v == 0
    assert peer.receive() == b"HELLO OPERATOR HELLO OPERATOR"
    assert plc.read("IW2,1,9") == 0  # no reception running any more


def test_4_4_buffer_fills_from_the_configuration_on() -> None:
    plc, mod, peer = fd()
    peer.send(b"abc")
    plc.advance(0.03)
    assert (plc.read("IW2,4"), plc.read("IW2,3")) == (3, ord("c"))
    rx = read(plc, 3)
    plc.advance(0.03)
    assert rx.result is not None and rx.result.data == b"abc"
    assert (plc.read("IW2,4"), plc.read("IW2,3")) == (0, 0)


def test_5_2_overflow_and_its_reset_bits() -> None:
    plc, mod, peer = fd()
    peer.send(b"a" * 254 + b"XY")
    plc.advance(0.5)
    assert plc.read("IW2,2,0") == 1 and plc.read("IW2,4") == 254  # AMB-SCM-15
    assert plc.read("IW2,3") == ord("Y")  # the last character, even though lost
    plc.write("OW2,1,8", 1)
    plc.advance(0.03)
    assert plc.read("IW2,2,0") == 0 and plc.read("IW2,4") == 254
    plc.write("OW2,1,8", 0)
    plc.write("OW2,1,B", 1)  # reset the reception buffer
    plc.advance(0.03)
    assert plc.read("IW2,4") == 0
    assert fault_bit_overload(plc)


def fault_bit_overload(plc: Plc) -> bool:
    r = plc.exchange(m=0x0263, c=0x47, recv_bytes=6, txt=31)
    return bool(int.from_bytes(r.data, "little") >> 47 & 1)  # 21: 3rd word bit F


@pytest.mark.parametrize("echo_type,expected", [(0, b"REWRITEAD"), (1, b"REWRITEREAD")])
def test_3_2_echo_type_table(echo_type: int, expected: bytes) -> None:
    # SCM 3.2 Echo type: "Read" received, interrupted by the transmission of "WRITE"
    plc, mod, peer = fd([0x1802, 0x9600, echo_type, 0x1000, 0, 0, 0, 0, 0])
    peer.send(b"RE")
    plc.advance(0.005)
    tx = write(plc, b"WRITE")
    for _ in range(20):
        plc.advance(0.001)
        if mod.channels[1].transmitting:
            break
    peer.send(b"AD")
    plc.advance(0.05)
    assert tx.result is not None and tx.result.v == 0
    assert peer.receive() == expected


def test_5_2_back_space_decrements_the_count_with_echo() -> None:
    plc, mod, peer = fd([0x1802, 0x9600, 0, 0x1001, 0, 0, 0, 0, 0])
    peer.send(b"ab")
    plc.advance(0.02)
    assert plc.read("IW2,4") == 2
    peer.send(b"\x08")
    plc.advance(0.02)
    assert plc.read("IW2,4") == 1
    assert peer.receive() == b"ab\x08 \x08"


def test_4_5_silence_between_characters_report_3() -> None:
    plc, mod, peer = fd([0x1802, 0x9600, 0, 0, 0, 0, 0, 0, 0x0003])  # 3 characters of silence
    rx = read(plc, 10)
    plc.advance(0.02)
    peer.send(b"ab")
    plc.advance(0.002 + 0.0023)
    assert not rx.done  # 2 characters on the line + less than 3 of silence
    plc.advance(0.03)
    assert rx.result is not None and (rx.result.v, rx.result.data) == (3, b"ab")


def test_4_4_end_character_in_full_duplex() -> None:
    plc, mod, peer = fd([0x1802, 0x9600, 0, 0, 0x1000, 0x0D00, 0, 0, 0])
    peer.send(b"one\rtwo\r")
    plc.advance(0.03)
    first = plc.exchange(m=M1, c=0x07, send=[0, 20], recv_bytes=20)
    second = plc.exchange(m=M1, c=0x07, send=[0, 20], recv_bytes=20)
    assert (first.v, first.data, second.v, second.data) == (1, b"one", 1, b"two")


def test_3_2_xon_xoff_reception_flow() -> None:
    plc, mod, peer = fd([0x1802, 0x9600, 0x0010, 0, 0, 0, 0, 0, 0])  # XON-XOFF (R)
    rx = read(plc, 3)
    plc.advance(0.02)
    peer.send(b"abc")
    plc.advance(0.02)
    assert rx.result is not None and peer.receive() == bytes([XOFF])
    rx = read(plc, 3)
    plc.advance(0.02)
    assert peer.receive() == bytes([XON]) and not rx.done


def test_3_2_automatic_dtr() -> None:
    plc, mod, peer = fd([0x1802, 0x9600, 0x0100, 0, 0, 0, 0, 0, 0])  # DTR automatic
    assert mod.signals[1].dtr == 0  # ready to receive
    rx = read(plc, 2)
    plc.advance(0.02)
    peer.send(b"ab")
    plc.advance(0.02)
    assert rx.done and mod.signals[1].dtr == 1  # AMB-SCM-22: count reached, not ready
    read(plc, 2)
    plc.advance(0.02)
    assert mod.signals[1].dtr == 0


def test_5_2_reset_bits_cancel_read_and_write_separately() -> None:
    plc, mod, peer = fd()
    rx = read(plc, 5)
    mod.set_signal(1, "CTS", 1)  # hold the transmitter so the write stays in progress
    tx = write(plc, b"hold")
    plc.advance(0.03)
    assert plc.read("IW2,1,9") == 1 and plc.read("IW2,1,A") == 1
    plc.write("OW2,1,A", 1)  # reset the write exchange
    plc.advance(0.03)
    assert tx.result is not None and tx.result.e and tx.result.s == 1 and not rx.done
    plc.write("OW2,1,9", 1)  # reset the read exchange
    plc.advance(0.03)
    assert rx.result is not None and rx.result.e and rx.result.s == 1


def test_4_4_full_duplex_accepts_only_request_7() -> None:
    plc, mod, peer = fd()
    assert plc.exchange(m=M1, c=0x01, send_bytes=b"x").v == 0xFD


def test_4_4_write_time_out_and_read_time_out_bits() -> None:
    plc, mod, peer = fd()
    mod.set_signal(1, "CD", 1)  # CD inactive: the reception circuit is inhibited
    peer.send(b"lost")
    plc.advance(0.03)
    assert plc.read("IW2,4") == 0
    rx = plc.exchange(m=M1, c=0x07, send=[0x0001, 2], recv_bytes=4)  # 100 ms
    assert rx.v == 0xFD
    r = plc.exchange(m=0x0263, c=0x47, recv_bytes=6, txt=31)
    assert int.from_bytes(r.data, "little") >> 42 & 1  # channel 1 READ time-out (bit A)


def test_5_2_back_space_without_echo_is_counted_on_the_4_6_channel() -> None:
    # SCM 4.6 table (examples/scm.toml channel 1): back-space validated, no reception echo;
    # 5.2 note: only "if reception echo is configured" does a BS decrement IWxy,4
    plc, mod, peer = fd()
    peer.send(b"ab\x08")
    plc.advance(0.03)
    assert plc.read("IW2,4") == 3 and plc.read("IW2,3") == 0x08
    assert peer.receive() == b""  # no echo at all
