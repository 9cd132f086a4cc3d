"""The control server's thread: uvicorn serving the API while the runner runs the plant.

``ControlServer.start()`` binds the listening socket first (so the port is known
and a busy port is a clear error), then serves it from a daemon thread with its
own asyncio loop; ``close()`` asks uvicorn to finish and joins the thread
(bounded).  The simulation never runs on this thread: see fieldtwin.control.sim.
"""

from __future__ import annotations

import errno
import ipaddress
import secrets
import socket
import threading
import time
from collections.abc import Sequence

import uvicorn

from fieldtwin.control.app import create_app
from fieldtwin.control.resources import Control
from fieldtwin.control.sim import Sim
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.inbox import Inbox

DEFAULT_PORT = 8520  # the documented default control port (docs/control.md)
DEFAULT_HOST = "127.0.0.1"
START_WAIT_S = 10.0  # how long start() waits for uvicorn to serve
STOP_WAIT_S = 5.0


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def new_token() -> str:
    return secrets.token_urlsafe(24)


def _bind(host: str, port: int) -> socket.socket:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    # accepted connections inherit it (Linux): an answer's head and body leave at once,
    # not 40 ms apart behind the peer's delayed ACK
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    try:
        sock.bind((host, port))
        sock.listen(128)
    except OSError:
        sock.close()
        raise
    sock.set_inheritable(True)
    return sock


def bind_control(host: str, port: int, *, fallback: bool) -> socket.socket:
    """The listening socket; with ``fallback`` a busy port gives any free one."""
    try:
        return _bind(host, port)
    except OSError as exc:
        if fallback and exc.errno == errno.EADDRINUSE:
            return _bind(host, 0)
        raise ConfigError(
            f"--control-port {port}: cannot listen on {host}:{port} ({exc.strerror});"
            " allowed: a free port, 0 for any free port, or --no-control"
        ) from None


class ControlServer:
    """The API of one running plant, served on one socket."""

    def __init__(
        self,
        control: Control,
        inbox: Inbox,
        sock: socket.socket,
        token: str | None,
        *,
        allow_origins: Sequence[str] = (),
        lane: bool = True,
    ) -> None:
        self.control = control
        self.inbox = inbox
        self.token = token
        self._socket = sock
        host = sock.getsockname()[0]
        self.app = create_app(
            control, Sim(inbox), token=token, host=host, allow_origins=allow_origins, lane=lane
        )
        config = uvicorn.Config(
            self.app,
            log_level="warning",
            lifespan="off",
            access_log=False,
            # uvloop where installed (a dependency on POSIX), else asyncio's own loop: the
            # loop of this thread only (uvicorn makes it by a factory, no global policy)
            loop="auto",
            # the server faces its clients directly: no X-Forwarded-* header from a local
            # process rewrites a request's scheme or client (the Origin check reads the
            # scheme), and no Server header goes out (docs/decisions.md, "The control
            # API's PUT: its loop and uvicorn's options")
            proxy_headers=False,
            server_header=False,
            ws_max_size=65536,
            ws_per_message_deflate=False,  # the events are sent as they are (loopback)
        )
        self._server = uvicorn.Server(config)
        self._thread = threading.Thread(target=self._serve, name="fieldtwin-control", daemon=True)

    @property
    def url(self) -> str:
        host, port = self._socket.getsockname()[:2]
        shown = f"[{host}]" if ":" in host else host
        return f"http://{shown}:{port}"

    def _serve(self) -> None:
        self._server.run(sockets=[self._socket])

    def start(self) -> str:
        self._thread.start()
        deadline = time.monotonic() + START_WAIT_S
        while not self._server.started and self._thread.is_alive():
            if time.monotonic() > deadline:
                raise ConfigError(f"the control server did not start within {START_WAIT_S:g} s")
            time.sleep(0.01)
        if not self._server.started:
            raise ConfigError("the control server could not start")
        return self.url

    def close(self) -> None:
        self._server.should_exit = True
        if self._thread.is_alive():
            self._thread.join(STOP_WAIT_S)
        self._socket.close()


__all__ = ["DEFAULT_HOST", "DEFAULT_PORT", "ControlServer", "bind_control", "is_loopback"]
