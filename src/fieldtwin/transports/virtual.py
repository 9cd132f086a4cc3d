"""Virtual endpoints: what a replay opens instead of ptys, serial ports and TCP listeners.

``fieldtwin replay`` rebuilds a recorded plant and binds its ports as the
recording did, but nothing real may be opened (no port to collide with, no
device to be missing on another machine).  It hands ``Wiring().backends``
(fieldtwin.transports.backends) to the binder and to the PLC's host, which open
the virtual twins below: they are real transports in everything the plant sees
(``is_real`` stays True, so an RTU line keeps the relaxed timing of a real
line), but they have no descriptor and never receive.  The replay runner
(fieldtwin.runtime.replay) delivers the recorded input bytes itself and sees
what the plant sends through each transport's ``observe_sends``.
"""

from __future__ import annotations

from fieldtwin.transports.backends import Backends
from fieldtwin.transports.base import FdTransport, LineSettings, line_settings
from fieldtwin.transports.pty import PtyTransport
from fieldtwin.transports.serial import SerialTransport
from fieldtwin.transports.tcp import DEFAULT_MAX_CONNECTIONS, TcpListener, TcpTransport


class _Sending(FdTransport):
    """What every virtual transport shares: no descriptor, everything sent taken at
    once (its observer sees it), nothing ever received (the replay delivers the
    recorded bytes)."""

    def _write(self, data: bytes) -> int:
        return len(data)

    def receive(self) -> bytes:
        self._check_open("receive")
        return b""

    def fileno(self) -> int | None:
        return None

    def _release(self) -> None:
        pass


class VirtualPty(_Sending, PtyTransport):
    def __init__(self, number: int, settings: LineSettings | None) -> None:
        super(PtyTransport, self).__init__(f"pty:virtual/{number}")
        self.settings = settings or line_settings()
        self.peer_path = f"virtual/{number}"


class VirtualSerial(_Sending, SerialTransport):
    _port = None  # type: ignore[assignment]  # no pyserial object: never follows a format

    def __init__(self, device: str, settings: LineSettings | None) -> None:
        super(SerialTransport, self).__init__(f"serial:{device}")
        self.settings = settings or line_settings()
        self.peer_path = device


class VirtualConnection(_Sending, TcpTransport):
    """A connection a replay hands to a virtual listener's ``on_connect``."""

    def __init__(self, name: str) -> None:
        super(TcpTransport, self).__init__(name)
        self._on_release = None


class VirtualListener(TcpListener):
    """A listener nobody can reach: the replay makes its connections."""

    def __init__(self, host: str, port: int) -> None:
        self.name = f"tcp://{host}:{port}"
        self.address = (host, port)
        self.closed = False
        self.live = 0
        self.accepted = 0

    def accept(self) -> TcpTransport | None:
        return None

    def connection(self) -> VirtualConnection:
        self.accepted += 1
        return VirtualConnection(f"{self.name} <- virtual:{self.accepted}")

    def fileno(self) -> int:
        return -1

    def close(self) -> None:
        self.closed = True


class Wiring:
    """The virtual twins of one replay's endpoints (ptys numbered in opening order);
    ``backends`` opens them."""

    def __init__(self) -> None:
        self._count = 0
        self.backends = Backends(listen=self.listener, pty=self.pty, serial=self.serial, real=False)

    def _number(self) -> int:
        self._count += 1
        return self._count

    def listener(self, host: str, port: int, max_connections: int) -> VirtualListener:
        return VirtualListener(host, port)

    def pty(self, settings: LineSettings | None) -> VirtualPty:
        return VirtualPty(self._number(), settings)

    def serial(self, device: str, settings: LineSettings | None) -> VirtualSerial:
        return VirtualSerial(device, settings)


__all__ = [
    "DEFAULT_MAX_CONNECTIONS",
    "VirtualConnection",
    "VirtualListener",
    "VirtualPty",
    "VirtualSerial",
    "Wiring",
]
