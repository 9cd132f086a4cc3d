"""Modbus TCP: MBAP framing and the server session."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.errors import ProtocolError
from fieldtwin.modbus.mbap import MbapDecoder, MbapFrame, encode_mbap
from fieldtwin.modbus.model import Counter, Link, ReadWords, Request, WriteWord
from fieldtwin.modbus.pdu import decode_response, encode_request
from fieldtwin.modbus.session import TcpSession
from tests.modbus.modbus_fakes import TableDevice
from tests.modbus.modbus_strategies import small_requests

READ = encode_request(ReadWords(3, 2, 1))


def test_mbap_golden_frame() -> None:
    # transaction 0001h, protocol 0, length 6 (unit + 5 PDU bytes), unit 11h.
    assert encode_mbap(1, 0x11, READ) == bytes.fromhex("0001 0000 0006 11 03 0002 0001")


frames_st = st.builds(
    MbapFrame, st.integers(0, 0xFFFF), st.integers(0, 255), st.binary(min_size=1, max_size=253)
)


@given(st.lists(frames_st, max_size=8), st.lists(st.integers(1, 40), max_size=30))
def test_frames_cut_anywhere_are_rebuilt_in_order(frames: list[MbapFrame], cuts: list[int]) -> None:
    stream = b"".join(encode_mbap(f.transaction, f.unit, f.pdu) for f in frames)
    decoder, out, pos = MbapDecoder(), [], 0
    for cut in cuts:
        out += decoder.feed(stream[pos : pos + cut])
        pos += cut
    out += decoder.feed(stream[pos:])
    assert out == frames and decoder.pending == 0


@pytest.mark.parametrize("length", [0, 1, 255, 0xFFFF])
def test_a_length_outside_2_254_is_a_protocol_error(length: int) -> None:
    with pytest.raises(ProtocolError, match=r"outside 2\.\.254"):
        MbapDecoder().feed(bytes.fromhex("0001 0000") + length.to_bytes(2, "big") + b"\x01")


def session(*devices: TableDevice) -> TcpSession:
    return TcpSession(devices)


def test_transaction_id_and_unit_are_echoed() -> None:
    s = session(TableDevice(1), TableDevice(2))
    s.receive(encode_mbap(0xBEEF, 2, READ), 100)
    [reply] = s.poll(100)
    assert reply.at == 100
    assert reply.data == bytes.fromhex("beef 0000 0005 02 03 02 0002")


def test_several_frames_in_one_read_and_a_partial_one() -> None:
    device = TableDevice(1)
    s = session(device)
    stream = b"".join(encode_mbap(t, 1, READ) for t in range(3))
    s.receive(stream + encode_mbap(3, 1, READ)[:5], 0)
    assert [r.data[:2] for r in s.poll(0)] == [b"\x00\x00", b"\x00\x01", b"\x00\x02"]
    s.receive(encode_mbap(3, 1, READ)[5:], 1)
    assert [r.data[:2] for r in s.poll(1)] == [b"\x00\x03"]
    assert device.counted(Counter.FRAMES_EXECUTED, Link.TCP) == 4


def test_answer_delay_applies_on_tcp() -> None:
    s = session(TableDevice(1, delay_us=2000))
    s.receive(encode_mbap(1, 1, READ), 0)
    assert s.poll(1999) == [] and s.next_deadline() == 2000
    assert len(s.poll(2000)) == 1


def test_unknown_unit_gets_gateway_exception_0b() -> None:
    s = session(TableDevice(1), TableDevice(2))
    s.receive(encode_mbap(7, 9, READ), 0)
    assert [r.data for r in s.poll(0)] == [bytes.fromhex("0007 0000 0003 09 83 0b")]


def test_unit_ff_reaches_a_lone_device() -> None:
    s = session(TableDevice(5))
    s.receive(encode_mbap(7, 0xFF, READ), 0)
    assert [r.data for r in s.poll(0)] == [bytes.fromhex("0007 0000 0005 ff 03 02 0002")]


def test_unit_0_is_a_broadcast_write_without_reply() -> None:
    one, two = TableDevice(1), TableDevice(2)
    s = session(one, two)
    s.receive(encode_mbap(7, 0, encode_request(WriteWord(3, 99))), 0)
    assert s.poll(0) == [] and one.words[3] == two.words[3] == 99


def test_other_protocol_ids_are_ignored() -> None:
    s = session(TableDevice(1))
    s.receive(encode_mbap(7, 1, READ, protocol=1), 0)
    assert s.poll(0) == [] and not s.closed


def test_a_broken_stream_closes_the_session() -> None:
    s = session(TableDevice(1))
    s.receive(bytes.fromhex("0001 0000 0000 01"), 0)
    assert s.closed and s.close_reason is not None and "length 0" in s.close_reason
    s.receive(encode_mbap(1, 1, READ), 1)
    assert s.poll(1) == []


@given(st.lists(small_requests, min_size=1, max_size=10))
def test_pipelined_requests_are_answered_in_order(requests: list[Request]) -> None:
    s = session(TableDevice(1))
    stream = b"".join(encode_mbap(i, 1, encode_request(r)) for i, r in enumerate(requests))
    s.receive(stream, 0)
    replies = s.poll(0)
    assert [int.from_bytes(r.data[:2], "big") for r in replies] == list(range(len(requests)))
    for reply, request in zip(replies, requests, strict=True):
        decode_response(request, reply.data[7:])
