"""LineSettings: character time and validation."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.errors import ConfigError
from fieldtwin.transports.base import LineSettings, line_settings


@pytest.mark.parametrize(
    ("settings", "bits", "char_us"),
    [
        (line_settings(), 10, 1042),  # 9600 8N1: 1041.67 us
        (line_settings(9600, 8, "E", 1), 11, 1146),  # 1145.83 us
        (line_settings(19200, 8, "E", 1), 11, 573),  # 572.92 us
        (line_settings(19200, 7, "O", 2), 11, 573),
        (line_settings(38400, 8, "N", 1), 10, 260),  # 260.42 us
        (line_settings(1200, 7, "N", 1), 9, 7500),
        (line_settings(300, 8, "N", 2), 11, 36667),  # 36666.67 us
    ],
)
def test_char_time(settings: LineSettings, bits: int, char_us: int) -> None:
    assert settings.bits == bits
    assert settings.char_time_us == char_us


@given(
    baud=st.integers(1, 10_000_000),
    data=st.sampled_from([7, 8]),
    parity=st.sampled_from(["N", "E", "O"]),
    stop=st.sampled_from([1, 2]),
)
def test_char_time_is_the_bit_count_over_baud_rounded(
    baud: int, data: int, parity: str, stop: int
) -> None:
    bits = 1 + data + (parity != "N") + stop
    char_us = line_settings(baud, data, parity, stop).char_time_us
    assert abs(char_us - bits * 1_000_000 / baud) <= 0.5


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"baud": 0}, r"baud=0: allowed a whole number > 0"),
        ({"baud": -9600}, r"baud=-9600"),
        ({"baud": 9600.0}, r"baud=9600.0"),
        ({"baud": True}, r"baud=True"),
        ({"data_bits": 6}, r"data_bits=6: allowed 7 or 8"),
        ({"parity": "X"}, r"parity='X': allowed N, E or O"),
        ({"parity": "e"}, r"parity='e'"),
        ({"stop_bits": 3}, r"stop_bits=3: allowed 1 or 2"),
    ],
)
def test_bad_values_name_the_field_and_the_allowed_values(
    kwargs: dict[str, object], message: str
) -> None:
    with pytest.raises(ConfigError, match=message):
        line_settings(**kwargs)  # type: ignore[arg-type]


def test_str() -> None:
    assert str(line_settings(19200, 8, "E", 1)) == "19200 8E1"
