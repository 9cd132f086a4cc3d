"""TCP on loopback (by default): a Listener for slaves, ``connect`` for masters.

Sockets are non-blocking with Nagle off (a Modbus answer leaves at once).
``receive`` on a connection whose peer has closed raises TransportError and
marks the transport closed, after returning whatever arrived before the close.
"""

from __future__ import annotations

import socket

from fieldtwin.errors import TransportError
from fieldtwin.transports.base import READ_CHUNK, FdTransport

CONNECT_TIMEOUT_S = 5.0


def _family(host: str) -> socket.AddressFamily:
    return socket.AF_INET6 if ":" in host else socket.AF_INET


def _hostport(address: tuple[str, int] | tuple[str, int, int, int]) -> str:
    host, port = address[0], address[1]
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


class TcpTransport(FdTransport):
    """One TCP connection."""

    def __init__(self, sock: socket.socket, name: str) -> None:
        super().__init__(name)
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock = sock
        self._fd = sock.fileno()

    def _write(self, data: bytes) -> int:
        return self._sock.send(data)

    def receive(self) -> bytes:
        """Bytes that arrived; b"" if none; TransportError once the peer has closed."""
        self._check_open("receive")
        self.flush()
        try:
            data = self._sock.recv(READ_CHUNK)
        except BlockingIOError:
            return b""
        except OSError as exc:
            self._broken(f"receive failed: {exc}")
        if not data:
            self._broken("the peer has closed the connection")
        return data

    def fileno(self) -> int | None:
        return None if self.closed else self._fd

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        self._out.clear()
        self._sock.close()


class TcpListener:
    """A listening socket; ``accept`` is non-blocking."""

    def __init__(self, host: str, port: int) -> None:
        sock = socket.socket(_family(host), socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((host, port))
            sock.listen()
            sock.setblocking(False)
        except OSError as exc:
            sock.close()
            raise TransportError(f"cannot listen on tcp://{host}:{port}: {exc}") from exc
        bound = sock.getsockname()
        self.address: tuple[str, int] = (str(bound[0]), int(bound[1]))
        self.name = f"tcp://{_hostport(self.address)}"
        self.closed = False
        self._sock = sock
        self._fd = sock.fileno()

    def __repr__(self) -> str:
        return f"<TcpListener {self.name} {'closed' if self.closed else 'listening'}>"

    def accept(self) -> TcpTransport | None:
        """A new connection, or None when nobody is waiting."""
        if self.closed:
            raise TransportError(f"cannot accept on {self.name}: it is closed")
        try:
            conn, remote = self._sock.accept()
        except (BlockingIOError, ConnectionAbortedError):
            return None
        return TcpTransport(conn, f"{self.name} <- {_hostport(remote)}")

    def fileno(self) -> int:
        return self._fd

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self._sock.close()


def listen(host: str = "127.0.0.1", port: int = 0) -> TcpListener:
    """Listen on ``host:port``; port 0 picks a free port (see ``.address``)."""
    return TcpListener(host, port)


def connect(host: str, port: int) -> TcpTransport:
    """Connect to ``host:port`` (blocking up to a few seconds, then non-blocking)."""
    try:
        sock = socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S)
    except OSError as exc:
        raise TransportError(f"cannot connect to tcp://{host}:{port}: {exc}") from exc
    local = _hostport(sock.getsockname())
    return TcpTransport(sock, f"tcp://{_hostport((host, port))} <- {local}")
