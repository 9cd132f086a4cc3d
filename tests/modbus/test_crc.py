"""CRC-16 vectors (TES 7.1.3, AMB-TES-03)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.modbus.crc import crc16, crc_bytes, crc_ok, with_crc


@pytest.mark.parametrize(
    ("frame", "crc"),
    [
        ("010300000001", "840a"),  # read 1 word at 0 from slave 1
        ("1103006b0003", "7687"),  # the Modbus RTU specification's example
        ("010600010003", "980b"),
        ("01050000ff00", "8c3a"),
        ("0107", "41e2"),  # TES 7.2.6 quick reading, Nq = 4
        ("0110000100020400010002", "e262"),
    ],
)
def test_crc_vectors_low_byte_first(frame: str, crc: str) -> None:
    data = bytes.fromhex(frame)
    assert crc_bytes(data).hex() == crc
    assert crc_ok(data + bytes.fromhex(crc))


def test_crc_of_nothing_is_the_initial_value() -> None:
    assert crc16(b"") == 0xFFFF


@given(st.binary(min_size=1, max_size=300))
def test_frame_with_its_crc_checks(data: bytes) -> None:
    assert crc_ok(with_crc(data))


@given(st.binary(min_size=2, max_size=260), st.data())
def test_any_single_byte_corruption_is_detected(data: bytes, draw: st.DataObject) -> None:
    frame = bytearray(with_crc(data))
    index = draw.draw(st.integers(0, len(frame) - 1))
    frame[index] ^= draw.draw(st.integers(1, 255))
    assert not crc_ok(frame)
