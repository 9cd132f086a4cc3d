"""Modbus PDU codec: requests and responses for fc 01..07, 0F, 10 (TES 7.1.1, 7.2).

A PDU is the function code and its data, without slave number and CRC (RTU) or
MBAP header (TCP).  Decoding a request never raises: a malformed or unsupported
PDU decodes to a ``Rejection`` carrying the exception code to answer with.
Decoding a *response* (the master side, for tests and clients) raises
``ProtocolError`` on bytes that do not fit the request.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from fieldtwin.errors import ProtocolError
from fieldtwin.modbus.model import (
    ExceptionCode,
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    Request,
    Result,
    WriteBit,
    WriteBits,
    WriteWord,
    WriteWords,
)

READ_COILS = 0x01
READ_DISCRETE_INPUTS = 0x02
READ_HOLDING = 0x03
READ_INPUT = 0x04
WRITE_COIL = 0x05
WRITE_REGISTER = 0x06
READ_EXCEPTION_STATUS = 0x07
WRITE_COILS = 0x0F
WRITE_REGISTERS = 0x10
EXCEPTION_FLAG = 0x80

# TES 7.1.1 function table (plus 04, AMB-TES-04).
FUNCTIONS = frozenset({1, 2, 3, 4, 5, 6, 7, 0x0F, 0x10})
WRITE_FUNCTIONS = frozenset({5, 6, 0x0F, 0x10})

# Modbus quantity limits; TES 7.2.4 gives "1 to 2000" for bit reads.
MAX_READ_BITS = 2000
MAX_READ_WORDS = 125
MAX_WRITE_BITS = 1968
MAX_WRITE_WORDS = 123
COIL_ON = 0xFF00
COIL_OFF = 0x0000

# AMB-TES-01: the TES lists only codes 1, 2 and 4, so bad quantities, byte
# counts, lengths and values are all answered with code 2.
DATA_FAULT = ExceptionCode.ILLEGAL_DATA_ADDRESS


@dataclass(frozen=True, slots=True)
class Rejection:
    """A request PDU the core answers with an exception without asking the device."""

    function: int
    code: ExceptionCode
    reason: str


def _u16(data: bytes, offset: int) -> int:
    return (data[offset] << 8) | data[offset + 1]


def _bits_to_bytes(values: tuple[bool, ...]) -> bytes:
    """Pack bits LSB first, ceil(n/8) bytes (TES 7.2.4, AMB-TES-07)."""
    out = bytearray((len(values) + 7) // 8)
    for i, value in enumerate(values):
        if value:
            out[i >> 3] |= 1 << (i & 7)
    return bytes(out)


def _bytes_to_bits(data: bytes, count: int) -> tuple[bool, ...]:
    return tuple(bool(data[i >> 3] >> (i & 7) & 1) for i in range(count))


def function_of(request: Request) -> int:
    """The function code a request is sent with."""
    match request:
        case ReadBits(function=fc) | ReadWords(function=fc):
            return fc
        case WriteBit():
            return WRITE_COIL
        case WriteWord():
            return WRITE_REGISTER
        case WriteBits():
            return WRITE_COILS
        case WriteWords():
            return WRITE_REGISTERS
        case ReadExceptionStatus():
            return READ_EXCEPTION_STATUS
    raise ProtocolError(f"not a Modbus request: {request!r}")


# --- requests: decode (slave side) ------------------------------------------------


def _reject(fc: int, reason: str, code: ExceptionCode = DATA_FAULT) -> Rejection:
    return Rejection(fc, code, reason)


def _range_fault(fc: int, address: int, count: int, limit: int) -> Rejection | None:
    if not 1 <= count <= limit:
        return _reject(fc, f"quantity {count} outside 1..{limit}")
    if address + count > 0x10000:
        return _reject(fc, f"address {address} + quantity {count} beyond FFFFh")
    return None


def _decode_read(fc: int, data: bytes) -> Request | Rejection:
    # TES 7.2.1 / 7.2.4: address of 1st item, number of items.
    if len(data) != 4:
        return _reject(fc, f"read request data is {len(data)} bytes, expected 4")
    address, count = _u16(data, 0), _u16(data, 2)
    limit = MAX_READ_BITS if fc in (READ_COILS, READ_DISCRETE_INPUTS) else MAX_READ_WORDS
    fault = _range_fault(fc, address, count, limit)
    if fault is not None:
        return fault
    if fc in (READ_COILS, READ_DISCRETE_INPUTS):
        return ReadBits(fc, address, count)
    return ReadWords(fc, address, count)


def _decode_single(fc: int, data: bytes) -> Request | Rejection:
    # TES 7.2.3 (fc06, AMB-TES-06) and fc05 (AMB-TES-05): address, value.
    if len(data) != 4:
        return _reject(fc, f"single write data is {len(data)} bytes, expected 4")
    address, value = _u16(data, 0), _u16(data, 2)
    if fc == WRITE_REGISTER:
        return WriteWord(address, value)
    if value not in (COIL_ON, COIL_OFF):
        return _reject(fc, f"bit value {value:04X}h is neither FF00h nor 0000h")
    return WriteBit(address, value == COIL_ON)


def _decode_multiple(fc: int, data: bytes) -> Request | Rejection:
    # TES 7.2.2 / 7.2.5: address, quantity, byte count, values.
    if len(data) < 5:
        return _reject(fc, f"multiple write data is {len(data)} bytes, expected >= 5")
    address, count, byte_count = _u16(data, 0), _u16(data, 2), data[4]
    limit = MAX_WRITE_BITS if fc == WRITE_COILS else MAX_WRITE_WORDS
    fault = _range_fault(fc, address, count, limit)
    if fault is not None:
        return fault
    expected = (count + 7) // 8 if fc == WRITE_COILS else 2 * count
    if byte_count != expected or len(data) != 5 + expected:
        return _reject(fc, f"byte count {byte_count} / {len(data) - 5} bytes, expected {expected}")
    values = data[5:]
    if fc == WRITE_COILS:
        return WriteBits(address, _bytes_to_bits(values, count))
    return WriteWords(address, struct.unpack(f">{count}H", values))


def decode_request(pdu: bytes) -> Request | Rejection:
    """A request PDU -> a typed request, or the exception to answer (never raises)."""
    if not pdu:
        return _reject(0, "empty PDU", ExceptionCode.ILLEGAL_FUNCTION)
    fc, data = pdu[0], bytes(pdu[1:])
    if fc not in FUNCTIONS:
        # TES 7 error codes: "1 = function code used by master is unknown".
        return _reject(fc, f"function {fc:02X}h unknown", ExceptionCode.ILLEGAL_FUNCTION)
    if fc <= READ_INPUT:
        return _decode_read(fc, data)
    if fc in (WRITE_COIL, WRITE_REGISTER):
        return _decode_single(fc, data)
    if fc == READ_EXCEPTION_STATUS:
        # TES 7.2.6: slave number, 07, CRC -- no data.
        return ReadExceptionStatus() if not data else _reject(fc, "fc07 request carries data")
    return _decode_multiple(fc, data)


# --- requests: encode (master side) ------------------------------------------------


def encode_request(request: Request) -> bytes:
    """A typed request -> its PDU (TES 7.2)."""
    fc = function_of(request)
    match request:
        case ReadBits(address=a, count=n) | ReadWords(address=a, count=n):
            return bytes((fc,)) + a.to_bytes(2, "big") + n.to_bytes(2, "big")
        case WriteBit(address=a, value=v):
            value = COIL_ON if v else COIL_OFF
            return bytes((fc,)) + a.to_bytes(2, "big") + value.to_bytes(2, "big")
        case WriteWord(address=a, value=v):
            return bytes((fc,)) + a.to_bytes(2, "big") + v.to_bytes(2, "big")
        case WriteBits(address=a, values=vs):
            packed = _bits_to_bytes(vs)
            head = a.to_bytes(2, "big") + len(vs).to_bytes(2, "big")
            return bytes((fc,)) + head + bytes((len(packed),)) + packed
        case WriteWords(address=a, values=vs):
            body = b"".join(v.to_bytes(2, "big") for v in vs)
            head = a.to_bytes(2, "big") + len(vs).to_bytes(2, "big")
            return bytes((fc,)) + head + bytes((len(body),)) + body
    return bytes((fc,))  # ReadExceptionStatus


# --- responses: encode (slave side) ------------------------------------------------


_READ_HEAD = struct.Struct(">BB")
_WRITE_ECHO = struct.Struct(">BHH")


def _words(values: tuple[int, ...] | tuple[bool, ...]) -> bytes:
    """Big-endian 16-bit words (struct.error if one is not 0..FFFFh)."""
    return struct.pack(f">{len(values)}H", *values)


def _echoable(request: WriteWords) -> bool:
    """Values and address that ``encode_request`` would encode without an error."""
    vs = request.values
    return (
        0 <= request.address <= 0xFFFF
        and 0 < 2 * len(vs) <= 0xFF
        and 0 <= min(vs) <= max(vs) <= 0xFFFF
    )


def encode_exception(function: int, code: int) -> bytes:
    """Exception response PDU: fc | 80h, code (AMB-TES-02)."""
    return bytes(((function | EXCEPTION_FLAG) & 0xFF, code & 0xFF))


def _bad_result(request: Request, result: Result) -> ProtocolError:
    return ProtocolError(f"device answered {result!r} to {request!r}")


def _encode_read_result(request: ReadBits | ReadWords, result: Result) -> bytes:
    if not isinstance(result, tuple) or len(result) != request.count:
        raise _bad_result(request, result)
    if isinstance(request, ReadBits):
        body = _bits_to_bytes(tuple(bool(v) for v in result))
    else:
        try:  # the fast path: words packed at once, the same bytes
            return _READ_HEAD.pack(request.function, 2 * len(result)) + _words(result)
        except struct.error:
            pass  # not 16-bit words: the checks below name the bad result
        if not all(isinstance(v, int) and 0 <= v <= 0xFFFF for v in result):
            raise _bad_result(request, result)
        body = b"".join(int(v).to_bytes(2, "big") for v in result)
    # TES 7.2.1 / 7.2.4 reply: function, byte number, values.
    return bytes((request.function, len(body))) + body


def encode_response(request: Request, result: Result) -> bytes:
    """The normal response PDU to ``request`` given the device's ``result``.

    An ``ExceptionCode`` result gives the exception response.  A result of the
    wrong shape is the device's bug and raises ``ProtocolError``.
    """
    fc = function_of(request)
    if isinstance(result, ExceptionCode):
        return encode_exception(fc, result)
    if isinstance(request, ReadBits | ReadWords):
        return _encode_read_result(request, result)
    if isinstance(request, ReadExceptionStatus):
        # TES 7.2.6: the 8 low bits of the status word.
        if not isinstance(result, int) or isinstance(result, bool) or not 0 <= result <= 0xFF:
            raise _bad_result(request, result)
        return bytes((fc, result))
    if result is not None:
        raise _bad_result(request, result)
    # TES 7.2.2 / 7.2.3 / 7.2.5: write replies echo address and value/quantity.
    if isinstance(request, WriteWords) and _echoable(request):  # fast: values not encoded
        return _WRITE_ECHO.pack(WRITE_REGISTERS, request.address, len(request.values))
    return encode_request(request)[:5]


# --- responses: decode (master side) -----------------------------------------------


def decode_response(request: Request, pdu: bytes) -> Result:
    """A response PDU to ``request`` -> its result; ``ProtocolError`` if it does not fit."""
    fc = function_of(request)
    if len(pdu) == 2 and pdu[0] == fc | EXCEPTION_FLAG:
        try:
            return ExceptionCode(pdu[1])
        except ValueError:
            raise ProtocolError(f"unknown exception code {pdu[1]:02X}h") from None
    if not pdu or pdu[0] != fc:
        raise ProtocolError(f"response {pdu.hex()} does not answer function {fc:02X}h")
    if isinstance(request, ReadBits | ReadWords):
        return _decode_read_response(request, pdu)
    if isinstance(request, ReadExceptionStatus):
        if len(pdu) != 2:
            raise ProtocolError(f"fc07 response {pdu.hex()} is not 2 bytes")
        return pdu[1]
    if pdu != encode_request(request)[:5]:
        raise ProtocolError(f"write response {pdu.hex()} does not echo the request")
    return None


def _decode_read_response(request: ReadBits | ReadWords, pdu: bytes) -> Result:
    expected = (request.count + 7) // 8 if isinstance(request, ReadBits) else 2 * request.count
    if len(pdu) != 2 + expected or pdu[1] != expected:
        raise ProtocolError(f"read response {pdu.hex()} should carry {expected} bytes")
    body = pdu[2:]
    if isinstance(request, ReadBits):
        return _bytes_to_bits(body, request.count)
    return tuple(_u16(body, 2 * i) for i in range(request.count))


# --- RTU frame lengths (TES 7.2 Nq / Nr) -------------------------------------------


def request_length(frame: bytes | bytearray) -> int | None:
    """Nq, the RTU length of the request starting ``frame`` (None: not known yet)."""
    if len(frame) < 2:
        return None
    fc = frame[1]
    if fc in (1, 2, 3, 4, 5, 6):
        return 8  # TES 7.2.1 / 7.2.3 / 7.2.4: Nq = 8
    if fc == READ_EXCEPTION_STATUS:
        return 4  # TES 7.2.6: Nq = 4
    if fc in (WRITE_COILS, WRITE_REGISTERS):
        # TES 7.2.2: Nq = 9 + 2n; 7.2.5: Nq = 9 + n/8 -- the byte count is at offset 6.
        return 9 + frame[6] if len(frame) > 6 else None
    return None


def response_length(frame: bytes | bytearray) -> int | None:
    """Nr, the RTU length of the response starting ``frame`` (None: not known yet)."""
    if len(frame) < 2:
        return None
    fc = frame[1]
    if fc & EXCEPTION_FLAG:
        return 5
    if fc in (1, 2, 3, 4):
        return 5 + frame[2] if len(frame) > 2 else None  # TES 7.2.1 / 7.2.4: 5 + bytes
    if fc in (5, 6, WRITE_COILS, WRITE_REGISTERS):
        return 8
    if fc == READ_EXCEPTION_STATUS:
        return 5  # TES 7.2.6: Nr = 5
    return None
