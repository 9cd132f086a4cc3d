"""Issue 15: the Modbus fast paths send the bytes the general path sends.

Read replies packed with ``struct`` equal the word-by-word encoding; an FC16
echo equals the first five bytes of the request; a TCP session's replies with
no answer delay skip the outbox yet leave in the same order and at the same
instant as through it.
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fieldtwin.errors import ProtocolError
from fieldtwin.modbus.mbap import encode_mbap
from fieldtwin.modbus.model import ReadWords, WriteWords
from fieldtwin.modbus.pdu import decode_request, encode_request, encode_response
from fieldtwin.modbus.session import TcpSession
from tests.modbus.modbus_fakes import TableDevice

_words = st.lists(st.integers(0, 0xFFFF), min_size=1, max_size=125)


@given(_words, st.sampled_from((3, 4)))
def test_read_reply_bytes_are_the_word_by_word_ones(words: list[int], fc: int) -> None:
    request = ReadWords(fc, 0, len(words))
    body = b"".join(w.to_bytes(2, "big") for w in words)
    assert encode_response(request, tuple(words)) == bytes((fc, len(body))) + body


@pytest.mark.parametrize("bad", [(0x10000,), (-1,), (1.5,), ("x",)])
def test_a_read_result_that_is_not_words_is_still_named(bad: tuple[object, ...]) -> None:
    with pytest.raises(ProtocolError, match="device answered"):
        encode_response(ReadWords(3, 0, 1), bad)  # type: ignore[arg-type]


@given(st.integers(0, 0xFFFF), st.lists(st.integers(0, 0xFFFF), min_size=1, max_size=123))
def test_fc16_echo_and_decode(address: int, values: list[int]) -> None:
    request = WriteWords(address, tuple(values))
    pdu = encode_request(request)
    assert encode_response(request, None) == pdu[:5]
    if address + len(values) <= 0x10000:
        assert decode_request(pdu) == request


def _ask(session: TcpSession, tid: int, now: int) -> None:
    pdu = encode_request(ReadWords(3, tid, 1))
    session.receive(encode_mbap(tid, 1, pdu), now)


def test_replies_with_and_without_delay_keep_time_and_order() -> None:
    device = TableDevice(1)
    session = TcpSession([device])
    sent: list[tuple[int, int]] = []

    def poll(now: int) -> None:
        sent.extend((t.at, int.from_bytes(t.data[:2], "big")) for t in session.poll(now))

    _ask(session, 1, 0)  # no delay: at once
    assert session.next_deadline() == 0
    poll(0)
    device.delay_us = 500
    _ask(session, 2, 10)  # due at 510
    device.delay_us = 0
    _ask(session, 3, 20)  # due at 20, behind a delayed one: the outbox keeps the order
    assert session.next_deadline() == 20
    poll(20)
    _ask(session, 4, 600)
    poll(600)
    assert sent == [(0, 1), (20, 3), (510, 2), (600, 4)]
    assert session.next_deadline() is None
