"""Configuration tables (AEM 3.2-3, 3.3, 3.4-1, 3.5-1, 5.1) and every rule of AEM 3.4-3."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.tsx.aem811.config import (
    DEFAULT_CONFIG,
    ModuleConfig,
    Rejection,
    decode_mode,
    parse_configuration,
    read_configuration,
)
from fieldtwin.tsx.aem811.scaling import ChannelConfig, Scaling
from fieldtwin.words import to_unsigned, words_to_bytes

A, B, C = Scaling.INPUT_RANGE, Scaling.STANDARD, Scaling.USER


def parse(words: list[int], current: ModuleConfig = DEFAULT_CONFIG) -> ModuleConfig | Rejection:
    return parse_configuration(words_to_bytes(to_unsigned(w) for w in words), current)


def accepted(words: list[int], current: ModuleConfig = DEFAULT_CONFIG) -> ModuleConfig:
    result = parse(words, current)
    assert isinstance(result, ModuleConfig), result
    return result


def refused(words: list[int], current: ModuleConfig = DEFAULT_CONFIG) -> str:
    result = parse(words, current)
    assert isinstance(result, Rejection), result
    return result.reason


def test_3_3_default_configuration() -> None:
    assert DEFAULT_CONFIG.period == 10
    assert all(c == ChannelConfig(0, False, A, False) for c in DEFAULT_CONFIG.channels)
    channels = [w for ch in range(8) for w in (0x00C0 | ch, 0x00A0)]
    assert DEFAULT_CONFIG.words() == [0x00A0, 10, *channels]


def test_amb_aem_01_mode_word_nibbles() -> None:
    assert decode_mode(0x80C0) == ChannelConfig(8, False, C, False)
    assert decode_mode(0x21C0) == ChannelConfig(2, True, C, False)
    assert decode_mode(0x50A1) == ChannelConfig(5, False, A, True)  # AMB-AEM-02: 0/2 V
    assert decode_mode(0x40B0) == ChannelConfig(4, False, B, False)
    for word in (0x80C0, 0x21C0, 0x50A1, 0x40B0, 0x00C0):
        cfg = decode_mode(word)
        assert isinstance(cfg, ChannelConfig) and cfg.mode_word == word


def test_3_2_3_channel_2() -> None:
    cfg = accepted([0x00C2, 0x00C0, 8800, 880])
    assert cfg.channels[2] == ChannelConfig(0, False, C, False, 8800, 880)
    assert cfg.period == 10 and cfg.channels[0] == DEFAULT_CONFIG.channels[0]


CW_3_4_1 = [0x00A0, 30, 0x00C0, 0x50C0, 10000, 0, 0x00C1, 0x20C0, 10000, 0, 0x00C2, 0x20C0,
            10000, 0, 0x00C3, 0x20C0, 10000, 0, 0x00C4, 0x21C0, 20000, 0, 0x00C5, 0x21C0,
            20000, 0, 0x00C6, 0x21C0, 20000, 0, 0x00C7, 0x21C0]  # fmt: skip


def test_3_4_1_constant_table() -> None:
    # the terminal screen shows CW0..CW31; channel 7's limits are off the screen
    assert "channel" in refused(CW_3_4_1) or "limits" in refused(CW_3_4_1)
    cfg = accepted([*CW_3_4_1, 20000, 0])
    assert cfg.period == 30
    assert cfg.channels[0] == ChannelConfig(5, False, C, False, 10000, 0)
    assert cfg.channels[7] == ChannelConfig(2, True, C, False, 20000, 0)


CW_3_5_1 = [0x00A0, 30, 0x00C0, 0x80C0, 8000, 0, 0x00C1, 0x40B0, 0x00C2, 0x00C0, 1000, 0,
            0x00C3, 0x80C0, 5000, 0, 0x00C7, 0x50A1]  # fmt: skip


def test_3_5_1_five_channels_36_bytes() -> None:
    assert len(words_to_bytes(CW_3_5_1)) == 36
    cfg = accepted(CW_3_5_1)
    assert cfg.period == 30
    assert cfg.channels[0] == ChannelConfig(8, False, C, False, 8000, 0)
    assert cfg.channels[1] == ChannelConfig(4, False, B, False)
    assert cfg.channels[2] == ChannelConfig(0, False, C, False, 1000, 0)  # AMB-AEM-04
    assert cfg.channels[3] == ChannelConfig(8, False, C, False, 5000, 0)
    assert cfg.channels[7] == ChannelConfig(5, False, A, True)
    assert cfg.channels[4] == DEFAULT_CONFIG.channels[4]


CW_5_1 = [0x00A0, 30, 0x00C0, 0x80C0, 10000, 0, 0x00C1, 0x21C0, 20000, 0, 0x00C2, 0x80C0,
          10000, 0, 0x00C3, 0x21C0, 20000, 0, 0x00C4, 0x80C0, 10000, 0, 0x00C5, 0x21C0, 20000,
          0, 0x00C6, 0x80C0, 10000, 0, 0x00C7, 0x21C0, 20000, 0]  # fmt: skip


def test_5_1_cw0_34_as_printed() -> None:
    assert len(CW_5_1) == 34
    cfg = accepted(CW_5_1)
    for ch in range(8):
        expected = (
            ChannelConfig(8, False, C, False, 10000, 0)
            if ch % 2 == 0
            else ChannelConfig(2, True, C, False, 20000, 0)
        )
        assert cfg.channels[ch] == expected
    assert cfg.words() == CW_5_1


def test_installation_sheet_6_4() -> None:
    cfg = accepted([0x00A0, 80, 0x00C4, 0x81C0, 5000, 0, 0x00C3, 0x80C0, 5000, 0,
                    0x00C2, 0x00B1, 0x00C1, 0x40B1, 0x00C0, 0x80C0, 8000, 0])  # fmt: skip
    assert cfg.channels[4] == ChannelConfig(8, True, C, False, 5000, 0)
    assert cfg.channels[1] == ChannelConfig(4, False, B, True)


def test_zones_in_any_order_and_subset() -> None:
    cfg = accepted([0x00C5, 0x40B0, 0x00A0, 50])
    assert cfg.period == 50 and cfg.channels[5].scaling is B
    assert accepted([0x00A0, 8]).period == 8 and accepted([0x00A0, 32000]).period == 32000


@pytest.mark.parametrize(
    ("table", "why"),
    [
        ([0x00A0], "length"),  # 2 bytes: under the 2-word minimum
        ([0x00A0, 10] * 17 + [0x00A0, 10], "length"),  # 72 bytes > 68
        ([0x00A0, 7], "period"),
        ([0x00A0, 32001], "period"),
        ([0x00B0, 10], "identifier"),  # undefined code
        ([0x00C8, 0x00A0], "identifier"),  # channel 8
        ([0x00C0, 0x90A0], "range"),  # range 9
        ([0x00C0, 0x02A0], "processing"),
        ([0x00C0, 0x00D0], "scaling"),
        ([0x00C0, 0x00A2], "continuity"),
        ([0x00C0, 0x01A0], "square root"),  # sqrt with input range scaling
        ([0x00C0, 0x80A1, 0x00A0, 30], "current"),  # continuity on 4/20 mA
        ([0x00C0, 0x70B1, 0x00A0, 30], "current"),  # and on 0/20 mA
        ([0x00C0, 0x20A1], "period"),  # continuity with the default period 10
        ([0x00A0, 23, 0x00C0, 0x20A1], "period"),  # AMB-AEM-08: 23 refused
        ([0x00C0, 0x20C0, 500, 500], "limits"),  # limits equal
        ([0x00C0, 0x20C0, 500], "limits"),  # zone split: a limit missing
        ([0x00A0, 30, 0x00C0], "cut short"),  # zone split after its identifier
        ([0x00C0, 0x20C0], "limits"),  # user range without its limits
        ([0x00C0, 0x20B0, 1000, 0], "identifier"),  # limits with standard scaling
        ([0x00A0, 30, 0x00A0, 40], "twice"),
    ],
)
def test_3_4_3_rejections(table: list[int], why: str) -> None:
    assert why in refused(table)


def test_3_4_3_odd_byte_count_refused() -> None:
    assert isinstance(parse_configuration(bytes(5), DEFAULT_CONFIG), Rejection)


def test_continuity_boundary_24_accepted() -> None:
    cfg = accepted([0x00A0, 24, 0x00C0, 0x20A1])  # AMB-AEM-08 [P]
    assert cfg.channels[0].continuity
    # and a stored continuity test makes a later short period refused
    assert "period" in refused([0x00A0, 10], cfg)


def test_negative_and_inverted_limits() -> None:
    cfg = accepted([0x00C0, 0x00C0, -32768, 32767])
    assert (cfg.channels[0].high, cfg.channels[0].low) == (-32768, 32767)


def test_4_4_3_read_configuration() -> None:
    cfg = accepted(CW_3_5_1)
    full = read_configuration(cfg, b"", 68)
    assert full is not None and full == cfg.words()
    assert len(full) == 2 + 2 + 4 + 2 + 4 + 4 + 2 + 2 + 2  # ch 0,2,3 with limits
    assert read_configuration(cfg, b"", 30) == [0x00A0, 30]  # TSX 47-20: zone 1 only
    one = read_configuration(cfg, words_to_bytes([0x00C3]), 12)
    assert one == [0x00A0, 30, 0x00C3, 0x80C0, 5000, 0]
    assert read_configuration(cfg, words_to_bytes([0x12C1]), 12) == [0x00A0, 30, 0x00C1, 0x40B0]
    # AEM 4.4-3 footnote (*): a first word other than H'XXC0'..H'XXC7' asks for the
    # complete configuration (zone 1 only when the reception table cannot hold it)
    assert read_configuration(cfg, words_to_bytes([0x00C8]), 12) == [0x00A0, 30]
    assert read_configuration(cfg, bytes(4), 68) == full
    assert read_configuration(cfg, words_to_bytes([0x00B0, 0x00C1]), 68) == full
    assert read_configuration(cfg, b"\xc1", 68) == full  # one byte is not a word


channel_configs = st.builds(
    lambda r, sq, sc, hi, lo: ChannelConfig(
        r, sq and sc is not A, sc, False, hi if sc is C else 0, lo if sc is C else 0
    ),
    st.integers(0, 8),
    st.booleans(),
    st.sampled_from([A, B, C]),
    st.integers(1, 32767),
    st.integers(-32768, 0),
)


@given(st.integers(8, 32000), st.lists(channel_configs, min_size=8, max_size=8))
def test_round_trip(period: int, channels: list[ChannelConfig]) -> None:
    cfg = ModuleConfig(period, tuple(channels))
    assert accepted(cfg.words()) == cfg


@given(st.binary(max_size=80))
def test_any_bytes_give_a_config_or_a_reason(data: bytes) -> None:
    result = parse_configuration(data, DEFAULT_CONFIG)
    assert isinstance(result, ModuleConfig | Rejection)
