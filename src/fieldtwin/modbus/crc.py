"""Modbus CRC-16 (TES 7.1.3 "control word CRC16").

TES 7.1.3: the CRC is "calculated on 16 bits, from all bytes of the transmitted or
received frame, except the 2 bytes of control".  The manual draws the byte order
both ways ("PF pf" / "pf PF"); we follow AMB-TES-03: the standard Modbus CRC-16
(reflected polynomial A001h, initial value FFFFh), low byte sent first.
"""

from __future__ import annotations

_POLY = 0xA001


def _make_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ _POLY if crc & 1 else crc >> 1
        table.append(crc)
    return tuple(table)


_TABLE = _make_table()


def crc16(data: bytes | bytearray | memoryview) -> int:
    """The Modbus CRC-16 of ``data`` (TES 7.1.3, AMB-TES-03)."""
    crc = 0xFFFF
    table = _TABLE
    for byte in data:
        crc = (crc >> 8) ^ table[(crc ^ byte) & 0xFF]
    return crc


def crc_bytes(data: bytes | bytearray | memoryview) -> bytes:
    """The two control bytes of ``data``, low byte first (AMB-TES-03)."""
    return crc16(data).to_bytes(2, "little")


def with_crc(data: bytes) -> bytes:
    """``data`` followed by its two control bytes: a complete RTU frame."""
    return data + crc_bytes(data)


def crc_ok(frame: bytes | bytearray | memoryview) -> bool:
    """True when the last two bytes of ``frame`` are the CRC of the others.

    Running the CRC over a whole frame including its (low-first) control bytes
    gives zero exactly when they match.
    """
    return len(frame) >= 3 and crc16(frame) == 0
