"""SCM 3: writing, refusing, reading and keeping the channel configuration."""

from __future__ import annotations

import itertools

import pytest

from fieldtwin.tsx.scm.config import HALF_DUPLEX_BYTES, Refused, decode, speed_conflict
from fieldtwin.words import words_to_bytes
from tests.tsx.scm.helpers import CONFIG_3_3, CONFIG_4_6, PLAIN_HD, SLOT, configure, m, make


def test_3_3_write_configuration_example() -> None:
    # SCM 3.3: CW0..CW7 to channel 0 of the module in slot 7, TXT0,L = 16 -> H'00FE', S = 0
    plc, mod = make()
    assert plc.read("IW7,0,3") == 1 and plc.read("IW7,0,B") == 1  # available, none configured
    r = plc.exchange(m=0x0700, c=0x40, send=CONFIG_3_3)
    assert (r.v, r.s, r.e) == (0xFE, 0, False)
    plc.advance(0.02)
    assert plc.read("IW7,1,3") == 1 and plc.read("IW7,1,B") == 0
    assert plc.read("IW7,0,B") == 0  # AMB-SCM-5: 1 only while no channel is configured
    cfg = mod.configs[0]
    assert (cfg.baud, cfg.fmt.frame, cfg.rx_echo, cfg.back_space) == (9600, "8N2", True, True)
    assert cfg.erc.valid1 and not cfg.erc.incl1 and cfg.erc.char1 == 0x0D
    assert not cfg.etc.valid1 and not cfg.tx_echo


def test_6_3_read_configuration_returns_the_table() -> None:
    plc, _ = make()
    configure(plc, SLOT, 0, CONFIG_3_3)
    r = plc.exchange(m=0x0700, c=0x41, recv_bytes=16)
    assert (r.v, r.s) == (0x71, 16) and r.words == CONFIG_3_3
    r63 = plc.exchange(m=0x0763, c=0x41, recv_bytes=16)  # AMB-SCM-19: xy63 reads channel 0
    assert r63.words == CONFIG_3_3
    assert plc.exchange(m=0x0701, c=0x41, recv_bytes=16).v == 0xFD  # not configured


def _format_word(bits: int, parity: int, stop: int) -> int:
    return (bits << 8) | (parity << 4) | stop


ALLOWED = {(7, 2, 1), (7, 1, 1), (7, 2, 2), (7, 1, 2), (8, 2, 1), (8, 1, 1), (8, 0, 1), (8, 0, 2)}


@pytest.mark.parametrize("bits,parity,stop", list(itertools.product((7, 8), (0, 1, 2), (1, 2))))
def test_3_2_only_the_eight_formats(bits: int, parity: int, stop: int) -> None:
    table = words_to_bytes([_format_word(bits, parity, stop), 0x9600, 0, 0, 0, 0, 0, 0])
    if (bits, parity, stop) in ALLOWED:
        assert decode(table, 0, False).fmt.bits == 1 + bits + (parity > 0) + stop
    else:
        with pytest.raises(Refused):
            decode(table, 0, False)


@pytest.mark.parametrize(
    "channel,word,ok",
    [(0, 0x0150, True), (0, 0x0075, False), (1, 0x0075, True), (1, 0x0150, False),
     (0, 0x1920, True), (0, 0x19200 & 0xFFFF, False), (1, 0x9600, True), (0, 0x110, False),
     (0, 0x96A0, False)],
)  # fmt: skip
def test_3_2_speed_lists_per_channel(channel: int, word: int, ok: bool) -> None:
    table = words_to_bytes([0x0802, word, 0, 0, 0, 0, 0, 0])
    if ok:
        decode(table, channel, False)
    else:
        with pytest.raises(Refused):
            decode(table, channel, False)


def test_3_2_two_channel_speed_restrictions() -> None:
    assert speed_conflict(19200, 9600) and not speed_conflict(19200, 4800)
    assert speed_conflict(9600, 19200) and not speed_conflict(9600, 9600)
    plc, mod = make()
    assert configure(plc, SLOT, 0, [0x0802, 0x1920, 0, 0, 0, 0, 0, 0]).v == 0xFE
    assert configure(plc, SLOT, 1, [0x0802, 0x9600, 0, 0, 0, 0, 0, 0]).v == 0xFD  # AMB-SCM-4
    assert configure(plc, SLOT, 1, [0x0802, 0x4800, 0, 0, 0, 0, 0, 0]).v == 0xFE


def test_3_3_refused_configuration_erases_the_previous_one() -> None:
    # SCM 3.3 "H'00FD' ... the channel is not configured, any previous configuration is lost"
    plc, mod = make()
    configure(plc, SLOT, 0, CONFIG_3_3)
    bad = [0x0702, *CONFIG_3_3[1:]]  # 7 bits without parity: not one of the eight
    assert configure(plc, SLOT, 0, bad).v == 0xFD
    plc.advance(0.02)
    assert mod.configs[0] is None and plc.read("IW7,1,3") == 0 and plc.read("IW7,0,B") == 1


def test_3_3_length_must_be_16_or_18() -> None:
    plc, _ = make()
    r = plc.exchange(m=0x0700, c=0x40, send=CONFIG_3_3, length=14)
    assert r.v == 0xFD
    assert plc.exchange(m=0x0700, c=0x40, send=[*PLAIN_HD, 0]).v == 0xFD  # 18 bytes, function 0


def test_4_4_full_duplex_only_on_channel_1_of_a_21xy() -> None:
    plc, _ = make("TSX SCM 2011")
    assert configure(plc, SLOT, 1, CONFIG_4_6).v == 0xFD
    plc, _ = make("TSX SCM 2111")
    assert configure(plc, SLOT, 0, CONFIG_4_6).v == 0xFD
    assert configure(plc, SLOT, 1, CONFIG_4_6).v == 0xFE
    plc, _ = make("TSX SCM 2116")  # 7.3 (*): Uni-Telway channel, full-duplex cannot be used
    assert configure(plc, SLOT, 1, CONFIG_4_6).v == 0xFD


@pytest.mark.parametrize(
    "word,ok", [(0x1002, True), (0x1000, False), (0x10A0, False), (0x0000, True), (0x1999, True)]
)
def test_3_2_transmission_echo_time_out_bcd_1_to_999(word: int, ok: bool) -> None:
    table = words_to_bytes([0x0802, 0x9600, word, 0, 0, 0, 0, 0])
    assert len(table) == HALF_DUPLEX_BYTES
    if ok:
        assert (
            decode(table, 0, False).echo_timeout_us
            == (word & 0xFFF and int(f"{word & 0xFFF:X}")) * 50_000
        )
    else:
        with pytest.raises(Refused):
            decode(table, 0, False)


def test_3_2_end_characters_fit_7_bits() -> None:
    table = [0x0721, 0x9600, 0, 0, 0x1000, 0x8D00, 0, 0]
    assert configure(*make()[:1], SLOT, 0, table).v == 0xFD


def test_3_1_configuration_kept_through_a_power_break_for_the_battery_life() -> None:
    plc, mod = make()
    configure(plc, SLOT, 0, CONFIG_3_3)
    plc.power_break(5.0)
    plc.advance(1.1)
    assert mod.configs[0] is not None and plc.read("IW7,1,3") == 1
    assert mod.battery_us == 21 * 24 * 3600 * 1_000_000
    mod.battery_us = 2_000_000  # a shorter battery so that the test runs fast
    plc.power_break(3.0)  # longer than the battery life: configuration lost
    plc.advance(1.1)
    assert mod.configs[0] is None and plc.read("IW7,0,B") == 1


def test_3_1_no_default_configuration_requests_refused() -> None:
    plc, _ = make()
    assert plc.exchange(m=m(0), c=0x01, send_bytes=b"X").v == 0xFD
