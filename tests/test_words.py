"""Property tests and manual vectors for fieldtwin.words (16-bit words, BCD, bytes, H'..')."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.errors import ConfigError
from fieldtwin.words import (
    bcd_decode,
    bcd_encode,
    bits_to_word,
    bytes_to_words,
    format_hex,
    get_bit,
    is_bcd,
    nibble,
    parse_word,
    set_bit,
    to_signed,
    to_unsigned,
    words_to_bytes,
)

words = st.integers(0, 0xFFFF)
signed = st.integers(-0x8000, 0x7FFF)
bits = st.integers(0, 15)


# --- signed / unsigned -----------------------------------------------------------


@given(signed)
def test_signed_round_trip(value: int) -> None:
    assert to_signed(to_unsigned(value)) == value


@given(words)
def test_unsigned_round_trip(word: int) -> None:
    assert to_unsigned(to_signed(word)) == word
    assert to_unsigned(word) == word


@pytest.mark.parametrize("value", [-0x8001, 0x10000])
def test_to_unsigned_rejects_what_does_not_fit(value: int) -> None:
    with pytest.raises(ConfigError, match=r"allowed -32768\.\.65535"):
        to_unsigned(value)


def test_signed_vectors() -> None:
    # AEM 2.3-3: measurements are signed words -32768..+32767
    assert to_signed(0x8000) == -32768
    assert to_signed(0xFFFF) == -1
    assert to_unsigned(-200) == 0xFF38


# --- bits and nibbles ----------------------------------------------------------------


@given(words, bits, st.booleans())
def test_set_then_get_bit(word: int, bit: int, value: bool) -> None:
    changed = set_bit(word, bit, value)
    assert get_bit(changed, bit) == int(value)
    assert 0 <= changed <= 0xFFFF
    others = ~(1 << bit) & 0xFFFF
    assert changed & others == word & others


@given(st.integers(-0x8000, 0x1FFFF), bits, st.booleans())
def test_set_bit_always_returns_a_word(word: int, bit: int, value: bool) -> None:
    assert 0 <= set_bit(word, bit, value) <= 0xFFFF


@given(words)
def test_bits_to_word_round_trip(word: int) -> None:
    assert bits_to_word(get_bit(word, i) for i in range(16)) == word


@given(words)
def test_nibbles_rebuild_the_word(word: int) -> None:
    assert sum(nibble(word, i) << (4 * i) for i in range(4)) == word


def test_first_nibble_is_bits_3_to_0() -> None:
    # AEM 3.2-2 (AMB-AEM-01): H'80C0' = range 8, processing 0, scaling C, test 0
    assert [nibble(0x80C0, i) for i in range(4)] == [0x0, 0xC, 0x0, 0x8]


@pytest.mark.parametrize("bit", [-1, 16])
def test_bit_out_of_range(bit: int) -> None:
    with pytest.raises(ConfigError, match=r"allowed 0\.\.F"):
        get_bit(0, bit)
    with pytest.raises(ConfigError, match=r"allowed 0\.\.F"):
        set_bit(0, bit, True)


# --- BCD -------------------------------------------------------------------------------


@given(st.integers(0, 9999))
def test_bcd_round_trip(value: int) -> None:
    word = bcd_encode(value)
    assert is_bcd(word)
    assert bcd_decode(word) == value
    assert f"{word:04X}" == f"{value:04d}"  # H'9600' reads as 9600


@given(words)
def test_bcd_decode_accepts_exactly_the_bcd_words(word: int) -> None:
    if is_bcd(word):
        assert bcd_encode(bcd_decode(word)) == word
    else:
        with pytest.raises(ConfigError, match="is not BCD"):
            bcd_decode(word, field="speed")


def test_bcd_error_names_field_and_digit() -> None:
    # SCM 3.2: the transmission speed is BCD (H'9600' = 9600 bauds)
    assert bcd_decode(0x9600) == 9600
    with pytest.raises(ConfigError, match=r"speed: H'96A0' is not BCD \(digit A at nibble 1"):
        bcd_decode(0x96A0, field="speed")


@pytest.mark.parametrize("value", [-1, 10000])
def test_bcd_encode_range(value: int) -> None:
    with pytest.raises(ConfigError, match=r"allowed 0\.\.9999"):
        bcd_encode(value)


# --- bytes <-> words -------------------------------------------------------------------


@given(st.binary(max_size=64))
def test_bytes_words_round_trip(data: bytes) -> None:
    as_words = bytes_to_words(data)
    assert len(as_words) == (len(data) + 1) // 2
    assert words_to_bytes(as_words, len(data)) == data


@given(st.lists(words, max_size=32))
def test_words_bytes_round_trip(values: list[int]) -> None:
    assert bytes_to_words(words_to_bytes(values)) == values


def test_first_character_in_the_low_byte() -> None:
    # SCM 3.4 message tables: "1st character" in the low byte of the first word
    assert bytes_to_words(b"P1 FAULT") == [0x3150, 0x4620, 0x5541, 0x544C]
    assert bytes_to_words(b"ABC") == [0x4241, 0x0043]
    assert words_to_bytes([0x4241, 0x0043], 3) == b"ABC"
    assert words_to_bytes([-1]) == b"\xff\xff"


@pytest.mark.parametrize("length", [-1, 5])
def test_words_to_bytes_length_out_of_range(length: int) -> None:
    with pytest.raises(ConfigError):
        words_to_bytes([0x4241, 0x0043], length)


# --- H'00A0' ---------------------------------------------------------------------------


@given(words)
def test_hex_round_trip(word: int) -> None:
    text = format_hex(word)
    assert text == f"H'{word:04X}'"
    assert parse_word(text) == word
    assert parse_word(text.lower()) == word


@pytest.mark.parametrize(
    ("token", "word"),
    [
        ("H'00A0'", 0x00A0),
        ("H'563'", 0x0563),  # AEM 3.5-2 "H'563: slot 5 of rack 0"
        ("H’563", 0x0563),  # the manuals' typographic quote, closing quote omitted
        ("H’0040'", 0x0040),
        ("B'0802'", 0x0802),  # AMB-SCM-01
        ("h'ff'", 0x00FF),
        ("0x00A0", 0x00A0),
        ("-0x1", 0xFFFF),
        ("160", 160),
        ("-5", 0xFFFB),
        (" 65535 ", 0xFFFF),
    ],
)
def test_parse_word_vectors(token: str, word: int) -> None:
    assert parse_word(token) == word


@pytest.mark.parametrize("token", ["", "H''", "H'12345'", "Z'00'", "65536", "-32769", "1.5", "ten"])
def test_parse_word_rejects(token: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_word(token)
    assert repr(token) in str(info.value) or "does not fit" in str(info.value)
