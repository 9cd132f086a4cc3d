"""PDU codec: TES 7.2 frame layouts, exceptions, round trips, malformed input."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.errors import ProtocolError
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.model import (
    ExceptionCode,
    ReadBits,
    ReadExceptionStatus,
    ReadWords,
    Request,
    WriteBit,
    WriteBits,
    WriteWord,
    WriteWords,
)
from fieldtwin.modbus.pdu import (
    Rejection,
    decode_request,
    decode_response,
    encode_exception,
    encode_request,
    encode_response,
    request_length,
    response_length,
)
from fieldtwin.modbus.timing import reply_bytes, request_bytes
from tests.modbus.modbus_strategies import requests, result_for

# Golden frames laid out as TES 7.2 draws them (slave, function, data, CRC16).
GOLDEN = [
    # 7.2.1 read n words: slave 1, fc03, 1st word 0007h, 2 words; reply 4 bytes.
    (ReadWords(3, 0x0007, 2), (0x1234, 0xABCD), "01 03 0007 0002 75ca", "01 03 04 1234abcd 0020"),
    # 7.2.2 write n words: 1st word 0010h, 2 words, 4 bytes; reply echoes address, number.
    (WriteWords(0x0010, (1, 2)), None, "01 10 0010 0002 04 00010002 22a2", "01 10 0010 0002 400d"),
    # 7.2.3 write 1 word 0020h = 00FFh; the reply echoes it.
    (WriteWord(0x0020, 0x00FF), None, "01 06 0020 00ff c840", "01 06 0020 00ff c840"),
    # 7.2.4 read n bits from bit 7ADh (TES 7.1.2: bit D of word 7Ah), 10 bits; 2 bytes.
    (ReadBits(1, 0x07AD, 10), (True,) * 9 + (False,), "01 01 07ad 000a 2c98", "01 01 02 ff01 39cc"),
    # 7.2.5 write n bits: 1st bit 0000h, 3 bits in 1 byte.
    (WriteBits(0, (True, False, True)), None, "01 0f 0000 0003 01 05 4f54", "01 0f 0000 0003 15ca"),
    # 7.2.6 quick reading of 8 bits: Nq = 4, Nr = 5.
    (ReadExceptionStatus(), 0x81, "01 07 41e2", "01 07 81 e250"),
]


def _hex(text: str) -> bytes:
    return bytes.fromhex(text.replace(" ", ""))


@pytest.mark.parametrize(("request_", "result", "question", "answer"), GOLDEN)
def test_section_7_2_golden_frames(
    request_: Request, result: object, question: str, answer: str
) -> None:
    q, r = _hex(question), _hex(answer)
    assert with_crc(b"\x01" + encode_request(request_)) == q
    assert decode_request(q[1:-2]) == request_
    reply = encode_response(request_, result)  # type: ignore[arg-type]
    assert with_crc(b"\x01" + reply) == r
    assert decode_response(request_, r[1:-2]) == result
    # Nq / Nr of TES 7.2, and the framer's length rules agree with them.
    assert len(q) == request_bytes(request_) == request_length(q)
    assert len(r) == reply_bytes(request_) == response_length(r)


@given(requests)
def test_request_round_trip(request_: Request) -> None:
    assert decode_request(encode_request(request_)) == request_


@given(requests, st.data())
def test_response_round_trip(request_: Request, data: st.DataObject) -> None:
    result = data.draw(result_for(request_))
    assert decode_response(request_, encode_response(request_, result)) == result


@given(st.binary(max_size=300))
def test_any_pdu_decodes_to_a_request_or_a_rejection(pdu: bytes) -> None:
    outcome = decode_request(pdu)
    assert isinstance(outcome, Rejection) or encode_request(outcome) == pdu


@given(st.integers(0, 255).filter(lambda fc: fc not in {1, 2, 3, 4, 5, 6, 7, 15, 16}))
def test_section_7_unknown_function_is_code_1(fc: int) -> None:
    # TES 7: "1 = function code used by master is unknown".
    assert decode_request(bytes((fc, 0, 0, 0, 1))) == Rejection(
        fc, ExceptionCode.ILLEGAL_FUNCTION, f"function {fc:02X}h unknown"
    )


@pytest.mark.parametrize(
    "pdu",
    [
        "03 0000 0000",  # zero words
        "03 0000 007e",  # 126 words > 125
        "01 0000 07d1",  # 2001 bits > 2000 (TES 7.2.4: 1 to 2000)
        "03 ffff 0002",  # past FFFFh
        "03 0000",  # too short
        "03 0000 0001 00",  # too long
        "05 0001 1234",  # fc05 value neither FF00h nor 0000h
        "10 0000 0002 03 000100",  # byte count not 2n
        "0f 0000 0009 01 ff",  # byte count not ceil(n/8)
        "10 0000 0001 02 0001 00",  # more bytes than announced
        "07 00",  # fc07 carries no data
    ],
)
def test_amb_tes_01_malformed_requests_get_code_2(pdu: str) -> None:
    outcome = decode_request(_hex(pdu))
    assert isinstance(outcome, Rejection)
    assert outcome.code is ExceptionCode.ILLEGAL_DATA_ADDRESS
    assert outcome.function == _hex(pdu)[0]


def test_empty_pdu_is_rejected() -> None:
    assert isinstance(decode_request(b""), Rejection)


def test_exception_response_amb_tes_02() -> None:
    assert encode_exception(3, ExceptionCode.ILLEGAL_DATA_ADDRESS) == b"\x83\x02"
    assert encode_response(WriteBit(1, True), ExceptionCode.SLAVE_DEVICE_FAILURE) == b"\x85\x04"
    assert decode_response(ReadWords(3, 0, 1), b"\x83\x02") is ExceptionCode.ILLEGAL_DATA_ADDRESS


@pytest.mark.parametrize(
    ("request_", "result"),
    [
        (ReadWords(3, 0, 2), (1,)),
        (ReadWords(3, 0, 1), (0x10000,)),
        (ReadExceptionStatus(), 256),
        (ReadExceptionStatus(), True),
        (WriteWord(0, 1), (1,)),
    ],
)
def test_a_device_result_of_the_wrong_shape_is_a_protocol_error(
    request_: Request, result: object
) -> None:
    with pytest.raises(ProtocolError, match="device answered"):
        encode_response(request_, result)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("request_", "pdu"),
    [
        (ReadWords(3, 0, 1), "04 02 0001"),
        (ReadWords(3, 0, 2), "03 02 0001"),
        (WriteWord(1, 2), "06 0001 0003"),
        (ReadExceptionStatus(), "07"),
        (ReadWords(3, 0, 1), "83 63"),
    ],
)
def test_decode_response_refuses_what_does_not_answer(request_: Request, pdu: str) -> None:
    with pytest.raises(ProtocolError):
        decode_response(request_, _hex(pdu))


def test_write_bit_encodes_ff00_and_0000() -> None:
    # fc05, AMB-TES-05: FF00h = 1, 0000h = 0.
    assert encode_request(WriteBit(0x7AD, True)) == _hex("05 07ad ff00")
    assert decode_request(_hex("05 07ad 0000")) == WriteBit(0x7AD, False)


def test_lengths_unknown_until_enough_bytes() -> None:
    assert request_length(b"\x01") is None
    assert request_length(b"\x01\x10\x00\x00\x00\x01") is None  # byte count not yet there
    assert request_length(b"\x01\x41") is None
    assert response_length(b"\x01\x03") is None
    assert response_length(b"\x01\x83") == 5
