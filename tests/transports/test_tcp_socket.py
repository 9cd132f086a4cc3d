"""TCP specifics: loopback listener on a free port, non-blocking accept, names, errors."""

from __future__ import annotations

import socket
import time

import pytest

from fieldtwin.errors import TransportError
from fieldtwin.transports.tcp import TcpListener, TcpTransport, connect, listen


def _accept(listener: TcpListener) -> TcpTransport:
    end = time.monotonic() + 5.0
    while (conn := listener.accept()) is None:
        assert time.monotonic() < end, "nothing accepted within 5 s"
    return conn


def test_port_zero_reports_the_real_port() -> None:
    listener = listen()
    try:
        host, port = listener.address
        assert host == "127.0.0.1" and port > 0
        assert listener.name == f"tcp://127.0.0.1:{port}"
    finally:
        listener.close()


def test_accept_is_non_blocking_and_names_both_ends() -> None:
    listener = listen()
    try:
        assert listener.accept() is None
        client = connect(*listener.address)
        server = _accept(listener)
        port = listener.address[1]
        assert server.name.startswith(f"tcp://127.0.0.1:{port} <- 127.0.0.1:")
        assert client.name.startswith(f"tcp://127.0.0.1:{port} <- 127.0.0.1:")
        client.close()
        server.close()
    finally:
        listener.close()


def test_connecting_to_a_closed_port_raises_transport_error() -> None:
    listener = listen()
    port = listener.address[1]
    listener.close()
    with pytest.raises(TransportError, match=f"tcp://127.0.0.1:{port}"):
        connect("127.0.0.1", port)


def test_listening_on_a_busy_port_raises_transport_error() -> None:
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        with pytest.raises(TransportError, match="cannot listen"):
            listen("127.0.0.1", port)


def test_accept_after_close_raises() -> None:
    listener = listen()
    listener.close()
    listener.close()
    with pytest.raises(TransportError, match="closed"):
        listener.accept()


def test_ipv6_loopback_when_available() -> None:
    if not socket.has_ipv6:
        pytest.fail("this platform has no IPv6 support")  # pragma: no cover
    try:
        listener = listen("::1", 0)
    except TransportError:
        return  # IPv6 disabled in this container: listen reports it as a TransportError
    try:
        assert listener.name == f"tcp://[::1]:{listener.address[1]}"
        client = connect("::1", listener.address[1])
        server = _accept(listener)
        client.send(b"6")
        end = time.monotonic() + 5.0
        while (got := server.receive()) == b"":
            assert time.monotonic() < end
        assert got == b"6"
        client.close()
        server.close()
    finally:
        listener.close()
