"""The conformance suite every backend passes: memory, pty, tcp, serial-on-pty (DESIGN rule 5)."""

from __future__ import annotations

import random
import selectors
import time

import pytest

from fieldtwin.errors import TransportError
from tests.transports.conftest import Pair
from tests.transports.transport_pumping import DEADLINE_S, collect, flush, until

ALL_BYTES = bytes(range(256))  # raw mode: ^C, XON/XOFF, CR, LF, DEL all pass unchanged


def test_bytes_arrive_both_ways_in_order(pair: Pair) -> None:
    pair.a.send(ALL_BYTES[:100])
    pair.a.send(ALL_BYTES[100:])
    assert collect(pair.b, pair.a, 256) == ALL_BYTES
    pair.b.send(ALL_BYTES[::-1])
    assert collect(pair.a, pair.b, 256) == ALL_BYTES[::-1]


@pytest.mark.parametrize("direction", ["a_to_b", "b_to_a"])
def test_large_payload_arrives_complete(pair: Pair, direction: str) -> None:
    tx, rx = (pair.a, pair.b) if direction == "a_to_b" else (pair.b, pair.a)
    payload = random.Random(7).randbytes(64 * 1024)
    tx.send(payload)  # never blocks: what the kernel refuses is queued
    assert collect(rx, tx, len(payload)) == payload


def test_receive_is_non_blocking_and_empty_when_idle(pair: Pair) -> None:
    start = time.monotonic()
    assert pair.a.receive() == b""
    assert pair.b.receive() == b""
    assert time.monotonic() - start < DEADLINE_S


def test_own_close_makes_send_and_receive_raise(pair: Pair) -> None:
    pair.a.close()
    assert pair.a.closed
    assert pair.a.fileno() is None
    with pytest.raises(TransportError, match="closed"):
        pair.a.send(b"x")
    with pytest.raises(TransportError, match="closed"):
        pair.a.receive()
    pair.a.close()  # closing twice is harmless


def test_peer_close(pair: Pair) -> None:
    pair.b.send(b"last words")
    got = collect(pair.a, pair.b, len(b"last words"))
    pair.b.close()
    if pair.peer_close_seen:

        def raised() -> bool:
            try:
                pair.a.receive()
            except TransportError:
                return True
            return False

        until(raised)
        assert pair.a.closed
    else:  # our pty end outlives its peers: one may reopen the slave later
        assert pair.a.receive() == b""
        assert not pair.a.closed
    assert got == b"last words"


def test_bytes_sent_before_peer_close_are_received_first(pair: Pair) -> None:
    pair.b.send(b"bye")
    flush(pair.b)
    if pair.backend in ("memory", "tcp"):
        pair.b.close()
    assert collect(pair.a, pair.b, 3) == b"bye"


def test_fileno_works_with_selectors(pair: Pair) -> None:
    fd = pair.a.fileno()
    if not pair.a.is_real:
        assert fd is None  # memory: polled, never selected
        return
    assert fd is not None
    with selectors.DefaultSelector() as selector:
        selector.register(fd, selectors.EVENT_READ)
        assert selector.select(0) == []
        pair.b.send(b"ping")
        flush(pair.b)
        ready = selector.select(DEADLINE_S)
    assert [key.fd for key, _ in ready] == [fd]
    assert collect(pair.a, pair.b, 4) == b"ping"


def test_identity(pair: Pair) -> None:
    assert pair.a.name and pair.b.name
    assert pair.a.is_real == (pair.backend != "memory")
    assert not pair.a.closed and not pair.b.closed
