"""Modbus TCP framing: the MBAP header (Modbus Messaging on TCP/IP, 3.1.3).

Transaction id (2 bytes, echoed in the reply), protocol id (2, always 0),
length (2, the unit id and PDU bytes that follow), unit id (1), then the PDU.
A TCP stream may cut frames anywhere and carry several in one read: the
decoder keeps the partial rest.  A length outside 2..254 cannot be
resynchronised and raises ``ProtocolError`` (the session then closes).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from fieldtwin.errors import ProtocolError

HEADER = 7
_HEAD = struct.Struct(">HHHB")  # transaction, protocol, length, unit
MIN_LENGTH = 2  # unit id + function code
MAX_LENGTH = 254  # unit id + the 253-byte maximum PDU
MODBUS_PROTOCOL = 0


@dataclass(frozen=True, slots=True)
class MbapFrame:
    """One Modbus TCP application data unit."""

    transaction: int
    unit: int
    pdu: bytes
    protocol: int = MODBUS_PROTOCOL


def encode_mbap(transaction: int, unit: int, pdu: bytes, protocol: int = MODBUS_PROTOCOL) -> bytes:
    """MBAP header + PDU."""
    if not 0 <= transaction <= 0xFFFF or not 0 <= unit <= 0xFF:
        raise ProtocolError(f"MBAP transaction {transaction} / unit {unit} out of range")
    length = len(pdu) + 1
    if not MIN_LENGTH <= length <= MAX_LENGTH:
        raise ProtocolError(f"MBAP PDU of {len(pdu)} bytes: allowed 1..253")
    return _HEAD.pack(transaction, protocol, length, unit) + pdu


class MbapDecoder:
    """Cuts a TCP byte stream into MBAP frames."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self.partial = self._buf  # the same buffer (empty: no frame begun), read inline

    @property
    def pending(self) -> int:
        """Bytes of an unfinished frame held back."""
        return len(self._buf)

    def feed(self, data: bytes) -> list[MbapFrame]:
        """Add bytes; return every frame they complete, in order."""
        buf = self._buf
        if not buf and len(data) >= HEADER:  # the usual case: exactly one whole frame
            transaction, protocol, length, unit = _HEAD.unpack_from(data)
            if len(data) == HEADER - 1 + length and MIN_LENGTH <= length <= MAX_LENGTH:
                return [MbapFrame(transaction, unit, bytes(data[HEADER:]), protocol)]
        buf += data
        frames: list[MbapFrame] = []
        while len(buf) >= HEADER:
            length = (buf[4] << 8) | buf[5]
            if not MIN_LENGTH <= length <= MAX_LENGTH:
                head = bytes(buf[:HEADER]).hex()
                raise ProtocolError(f"MBAP header {head}: length {length} outside 2..254")
            end = HEADER - 1 + length
            if len(buf) < end:
                break
            frames.append(
                MbapFrame(
                    transaction=(buf[0] << 8) | buf[1],
                    unit=buf[6],
                    pdu=bytes(buf[HEADER:end]),
                    protocol=(buf[2] << 8) | buf[3],
                )
            )
            del buf[:end]
        return frames
