"""TCP on loopback (by default): a Listener for slaves, ``connect`` for masters.

A listener holds at most ``max_connections`` open connections (default
DEFAULT_MAX_CONNECTIONS).  At the limit a new connection takes the place of the
longest-idle one (no request received for the longest time) that its server
says is not in the middle of a request; when there is none, the new one is
closed at once.  A failed accept for want of descriptors or buffers raises
``AcceptFailed`` so the runner can back off instead of dying.

Sockets are non-blocking with Nagle off (a Modbus answer leaves at once).
``receive`` on a connection whose peer has closed raises TransportError and
marks the transport closed, after returning whatever arrived before the close.
"""

from __future__ import annotations

import errno
import socket
import struct
from collections import OrderedDict
from collections.abc import Callable
from contextlib import suppress
from functools import partial
from itertools import islice

from fieldtwin.errors import ConfigError, TransportError
from fieldtwin.transports.base import READ_CHUNK, AcceptFailed, FdTransport

CONNECT_TIMEOUT_S = 5.0
# Open connections per listening endpoint (issue 10 item 1); more are closed at once.
DEFAULT_MAX_CONNECTIONS = 256
# Issue 20 item 7: at the limit, the longest-idle connections looked at for one that
# may go (not in the middle of a request); so many at most, whatever the limit.
EVICT_PROBE = 8
LISTEN_BACKLOG = 128
ACCEPT_BATCH = 64  # connections looked at per accept() call, refused ones included
# Issue 10 item 3, fairness: a read holds at most 2 KiB of requests (170 reads of 12
# bytes), so one pipelining peer costs one short slice of a cycle, never a long one,
# and the answers one read can queue stay small (see the runner's OUTPUT_BOUND).
TCP_READ_CHUNK = 2048
# The kernel's send buffer of an accepted connection (Linux doubles it): fixed and
# small, so that a peer that stops reading is noticed after a few dozen KiB of
# answers, not after megabytes of autotuned buffer.
SERVER_SEND_BUFFER = 16384
_EXHAUSTED = frozenset({errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM})


def _family(host: str) -> socket.AddressFamily:
    return socket.AF_INET6 if ":" in host else socket.AF_INET


def _hostport(address: tuple[str, int] | tuple[str, int, int, int]) -> str:
    host, port = address[0], address[1]
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def listener_url(scheme: str, address: tuple[str, int] | tuple[str, int, int, int]) -> str:
    """``scheme://HOST:PORT`` for a bound address, IPv6 in brackets so that it parses
    back (``tcp://[::]:25951``, not ``tcp://:::25951``)."""
    return f"{scheme}://{_hostport(address)}"


class TcpTransport(FdTransport):
    """One TCP connection."""

    # Issue 20 item 7: set by the server that reads an accepted connection; True while
    # a request is in progress (its answer not yet sent).  None: its server never
    # said, so its listener never closes it to make room for a new one.
    in_progress: Callable[[], bool] | None = None
    # the listener's open connections, least recently active first (None: not accepted)
    _recency: OrderedDict[int, TcpTransport] | None = None

    def __init__(
        self, sock: socket.socket, name: str, on_release: Callable[[], None] | None = None
    ) -> None:
        super().__init__(name)
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock = sock
        self._fd = sock.fileno()
        self._on_release = on_release  # the listener's count of live connections

    def _write(self, data: bytes) -> int:
        return self._sock.send(data)

    def send(self, data: bytes) -> None:
        """``FdTransport.send``, its usual case (nothing queued, nobody observing) in
        one call: a Modbus reply per request makes it the hottest call of a server."""
        if self.closed or self._sends is not None or self._out or len(data) > READ_CHUNK:
            super().send(data)
            return
        try:
            written = self._sock.send(data)
        except BlockingIOError:
            written = 0
        except OSError as exc:
            self._broken(f"write failed: {exc}")
        if written >= len(data):
            return
        self._out += data[written:]
        if self.watcher is not None:
            self.watcher.backlogged(self)

    def receive(self) -> bytes:
        """Bytes that arrived; b"" if none; TransportError once the peer has closed."""
        if self.closed:
            self._check_open("receive")
        if self._out:
            self.flush()
        try:
            data = self._sock.recv(TCP_READ_CHUNK)
        except BlockingIOError:
            return b""
        except OSError as exc:
            self._broken(f"receive failed: {exc}")
        if not data:
            self._broken("the peer has closed the connection")
        recency = self._recency
        if recency is not None:  # a request: the most recently active connection now
            recency.move_to_end(id(self))
        return data

    def hang_up(self) -> None:
        """Close with a FIN (an orderly end the peer sees as such), not a reset."""
        if not self.closed:
            with suppress(OSError):
                self._sock.shutdown(socket.SHUT_RDWR)
            self.close()

    def fileno(self) -> int | None:
        return None if self.closed else self._fd

    def _release(self) -> None:
        self._sock.close()
        if self._on_release is not None:
            self._on_release()
            self._on_release = None


class TcpListener:
    """A listening socket; ``accept`` is non-blocking.

    At most ``max_connections`` accepted connections are open at once.  One
    more takes the place of the longest-idle open connection (no request
    received for the longest time; accepted counts as a request) whose
    ``in_progress`` says no request is in progress and that has no answer
    queued: that one is hung up with a FIN (counted in ``evicted``).  Only the
    ``EVICT_PROBE`` longest-idle connections are looked at; when none of them
    may go, the new one is closed at once (counted in ``refused``).  An accept
    that fails for want of resources raises ``AcceptFailed``; one that fails
    for the waiting connection's own reasons (it was reset, a network error
    pending on it) is skipped.
    """

    def __init__(
        self, host: str, port: int, max_connections: int = DEFAULT_MAX_CONNECTIONS
    ) -> None:
        if isinstance(max_connections, bool) or max_connections < 1:
            raise ConfigError(f"max_connections={max_connections!r}: allowed a whole number > 0")
        sock = socket.socket(_family(host), socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((host, port))
            sock.listen(LISTEN_BACKLOG)
            sock.setblocking(False)
        except OSError as exc:
            sock.close()
            raise TransportError(f"cannot listen on tcp://{host}:{port}: {exc}") from exc
        bound = sock.getsockname()
        self.address: tuple[str, int] = (str(bound[0]), int(bound[1]))
        self.name = listener_url("tcp", self.address)
        self.closed = False
        self.max_connections = max_connections
        self.live = 0  # accepted connections still open
        self.refused = 0  # connections closed at once: the limit was reached
        self.evicted = 0  # idle connections hung up to make room for a new one
        # open connections by id, least recently active first (O(1) per request)
        self._open: OrderedDict[int, TcpTransport] = OrderedDict()
        self._sock = sock
        self._fd = sock.fileno()

    def __repr__(self) -> str:
        return f"<TcpListener {self.name} {'closed' if self.closed else 'listening'}>"

    def accept(self) -> TcpTransport | None:
        """A new connection, or None when nobody (within the limit) is waiting."""
        if self.closed:
            raise TransportError(f"cannot accept on {self.name}: it is closed")
        for _ in range(ACCEPT_BATCH):
            try:
                conn, remote = self._sock.accept()
            except BlockingIOError:
                return None
            except OSError as exc:
                if exc.errno in _EXHAUSTED:
                    raise AcceptFailed(f"{self.name}: cannot accept a connection: {exc}") from exc
                continue  # accept(2): the waiting connection's own error; take the next
            if self.live >= self.max_connections and not self._evict_idle():
                self.refused += 1
                _close_at_once(conn)
                continue
            try:
                conn.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SERVER_SEND_BUFFER)
                transport = TcpTransport(conn, f"{self.name} <- {_hostport(remote)}")
            except OSError:  # reset before we could set it up: take the next
                conn.close()
                continue
            key = id(transport)
            transport._on_release = partial(self._released, key)
            transport._recency = self._open
            self._open[key] = transport
            self.live += 1
            return transport
        return None  # still readable: the next wait comes back here

    def _evict_idle(self) -> bool:
        """Hang up the longest-idle connection that may go; False if none may."""
        for transport in islice(self._open.values(), EVICT_PROBE):
            busy = transport.in_progress
            if busy is None or transport.pending_output or busy():
                continue
            transport.hang_up()  # its release takes it out of ``_open``
            self.evicted += 1
            return True
        return False

    def _released(self, key: int) -> None:
        self.live -= 1
        self._open.pop(key, None)

    def fileno(self) -> int:
        return self._fd

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self._sock.close()


def _close_at_once(conn: socket.socket) -> None:
    """Refuse an accepted connection: an RST, not a lingering FIN_WAIT."""
    with suppress(OSError):
        conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    conn.close()


def listen(
    host: str = "127.0.0.1", port: int = 0, max_connections: int = DEFAULT_MAX_CONNECTIONS
) -> TcpListener:
    """Listen on ``host:port``; port 0 picks a free port (see ``.address``)."""
    return TcpListener(host, port, max_connections)


def connect(host: str, port: int) -> TcpTransport:
    """Connect to ``host:port`` (blocking up to a few seconds, then non-blocking)."""
    try:
        sock = socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S)
    except OSError as exc:
        raise TransportError(f"cannot connect to tcp://{host}:{port}: {exc}") from exc
    local = _hostport(sock.getsockname())
    return TcpTransport(sock, f"tcp://{_hostport((host, port))} <- {local}")
