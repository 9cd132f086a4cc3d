"""Issue 20 item 7: at its connection limit a listener makes room for a new peer.

The longest-idle connection (no bytes received for the longest time) whose
server says no request is in progress is hung up with a FIN; a connection whose
server never said, one with an answer queued or one in the middle of a request
stays.  Real loopback sockets, the listener driven by hand (no runner).
"""

from __future__ import annotations

import select
import socket
from collections.abc import Iterator

import pytest

from fieldtwin.transports.tcp import EVICT_PROBE, TcpListener, TcpTransport, listen

WAIT_S = 5.0


@pytest.fixture
def listener() -> Iterator[TcpListener]:
    lst = listen("127.0.0.1", 0, max_connections=2)
    yield lst
    lst.close()


class Peers:
    """Client sockets and the transports the listener accepted for them."""

    def __init__(self, listener: TcpListener) -> None:
        self.listener = listener
        self.clients: list[socket.socket] = []
        self.accepted: list[TcpTransport | None] = []

    def connect(self) -> TcpTransport | None:
        """One more client; the transport accepted for it (None: closed at once)."""
        client = socket.create_connection(self.listener.address, timeout=WAIT_S)
        self.clients.append(client)
        before = (self.listener.refused, len(self.accepted))
        transport = None
        for _ in range(50):  # bounded: the handshake is done, accept finds it at once
            select.select([self.listener.fileno()], [], [], WAIT_S / 50)
            transport = self.listener.accept()
            if transport is not None or self.listener.refused > before[0]:
                break
        self.accepted.append(transport)
        return transport

    def close(self) -> None:
        for client in self.clients:
            client.close()
        for transport in self.accepted:
            if transport is not None:
                transport.close()


@pytest.fixture
def peers(listener: TcpListener) -> Iterator[Peers]:
    made = Peers(listener)
    yield made
    made.close()


def _idle(transport: TcpTransport | None) -> TcpTransport:
    assert transport is not None
    transport.in_progress = lambda: False
    return transport


def _hung_up_with_fin(client: socket.socket) -> bool:
    """The server ended the connection in order: recv sees the end (b""), not a reset."""
    client.settimeout(WAIT_S)
    return client.recv(1) == b""


def test_at_the_limit_the_longest_idle_connection_makes_room(
    listener: TcpListener, peers: Peers
) -> None:
    first, second = _idle(peers.connect()), _idle(peers.connect())
    third = peers.connect()
    assert third is not None and not third.closed
    assert first.closed and not second.closed
    assert listener.evicted == 1 and listener.refused == 0 and listener.live == 2
    assert _hung_up_with_fin(peers.clients[0])


def test_a_request_received_makes_a_connection_the_most_recent(
    listener: TcpListener, peers: Peers
) -> None:
    first, second = _idle(peers.connect()), _idle(peers.connect())
    peers.clients[0].sendall(b"\x00\x01")
    for _ in range(50):  # bounded wait for the bytes to arrive
        if first.receive():
            break
        select.select([first.fileno()], [], [], WAIT_S / 50)
    _idle(peers.connect())
    assert second.closed and not first.closed  # the second one was idle the longest


def test_a_connection_in_the_middle_of_a_request_is_never_hung_up(
    listener: TcpListener, peers: Peers
) -> None:
    first = peers.connect()
    assert first is not None
    first.in_progress = lambda: True  # its answer is due later
    second = _idle(peers.connect())
    third = peers.connect()
    assert third is not None
    assert not first.closed and second.closed  # the next longest-idle one went instead
    _idle(third)
    assert peers.connect() is not None
    assert third.closed and not first.closed


def test_a_connection_with_an_answer_queued_is_never_hung_up(
    listener: TcpListener, peers: Peers
) -> None:
    first, second = _idle(peers.connect()), _idle(peers.connect())
    first.send(b"\x00" * 8_000_000)  # the client never reads: most of it stays queued
    assert first.pending_output > 0
    assert peers.connect() is not None
    assert not first.closed and second.closed


def test_when_no_connection_may_go_the_new_one_is_refused(
    listener: TcpListener, peers: Peers
) -> None:
    first, second = peers.connect(), peers.connect()
    assert first is not None and second is not None
    first.in_progress = lambda: True
    # the second one's server never said whether it is busy: it is not hung up either
    assert peers.connect() is None
    assert listener.refused == 1 and listener.evicted == 0
    assert not first.closed and not second.closed


def test_only_the_first_few_longest_idle_connections_are_looked_at() -> None:
    listener = listen("127.0.0.1", 0, max_connections=EVICT_PROBE + 1)
    peers = Peers(listener)
    try:
        busy = [peers.connect() for _ in range(EVICT_PROBE)]
        for transport in busy:
            assert transport is not None
            transport.in_progress = lambda: True
        last = _idle(peers.connect())
        assert peers.connect() is None  # the idle one is beyond the probe: refused
        assert listener.refused == 1 and not last.closed
    finally:
        peers.close()
        listener.close()


def test_a_connection_that_closes_leaves_the_order(listener: TcpListener, peers: Peers) -> None:
    first, second = _idle(peers.connect()), _idle(peers.connect())
    first.close()
    assert listener.live == 1 and list(listener._open.values()) == [second]
    third = _idle(peers.connect())
    assert listener.evicted == 0 and not second.closed and not third.closed
