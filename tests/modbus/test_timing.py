"""TES 7.2.7 transmission time and the RTU silences."""

from __future__ import annotations

import pytest

from fieldtwin.charformat import CharFormat
from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import (
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    Request,
    WriteBit,
    WriteBits,
    WriteWord,
    WriteWords,
)
from fieldtwin.modbus.timing import (
    RtuTiming,
    bits_per_char,
    exchange_time_us,
    reply_bytes,
    request_bytes,
    request_exchange_time_us,
)
from fieldtwin.transports.base import line_settings


def test_section_7_2_7_one_word_write_at_38400_is_about_9_3_ms() -> None:
    # "T = ((8+1+1+1)1000/38.400) x (8 + 3 + 8 + 3) + 1,5 + 1,5 # 9,3 ms"
    assert exchange_time_us(11, 38400, nq=8, nr=8) == 9302
    assert round(exchange_time_us(11, 38400, nq=8, nr=8) / 1000, 1) == 9.3


def test_section_7_2_7_from_a_request_and_the_line_format() -> None:
    line = line_settings(baud=38400, data_bits=8, parity="E", stop_bits=1)
    assert bits_per_char(line) == 11
    assert request_exchange_time_us(WriteWord(0x10, 1), line) == 9302


def test_section_7_2_7_nb_is_8_to_11() -> None:
    with pytest.raises(ConfigError, match="Nb 12"):
        exchange_time_us(12, 9600, 8, 8)


def test_bad_format_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match="parity"):
        bits_per_char(CharFormat(9600, parity="X"))  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("request_", "nq", "nr"),
    [
        (ReadWords(3, 0, 10), 8, 5 + 20),  # TES 7.2.1: Nq = 8, Nr = 5 + 2n
        (WriteWords(0, (1, 2, 3)), 9 + 6, 8),  # TES 7.2.2: Nq = 9 + 2n, Nr = 8
        (WriteWord(0, 1), 8, 8),  # TES 7.2.3
        (ReadBits(1, 0, 9), 8, 5 + 2),  # TES 7.2.4: Nr = 5 + n/8 (AMB-TES-07: rounded up)
        (WriteBits(0, (True,) * 9), 9 + 2, 8),  # TES 7.2.5: Nq = 9 + n/8
        (ReadExceptionStatus(), 4, 5),  # TES 7.2.6
        (WriteBit(0, True), 8, 8),  # fc05, AMB-TES-05
    ],
)
def test_section_7_2_frame_lengths(request_: Request, nq: int, nr: int) -> None:
    assert request_bytes(request_) == nq
    assert reply_bytes(request_) == nr


def test_rtu_silences_from_the_line_format() -> None:
    timing = RtuTiming.from_format(line_settings(9600, 8, "E", 1))
    # 11 bits at 9600 baud: 1145.8 us per character.
    assert (timing.char_us, timing.t15_us, timing.t35_us) == (1146, 1719, 4010)


def test_relaxed_timing_keeps_t35_above_t15() -> None:
    timing = RtuTiming.from_format(line_settings(115200)).relaxed(5000, eager=True)
    assert timing.t15_us == 5000 and timing.t35_us == 10000 and timing.eager


def test_inconsistent_timing_is_refused() -> None:
    with pytest.raises(ConfigError):
        RtuTiming(100, 400, 300)
