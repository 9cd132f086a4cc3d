"""What opens a plant's endpoints: the real OS, or a replay's virtual twins.

A :class:`Backends` value maps each kind of endpoint to the function that opens
it.  The composition root chooses one and hands it down explicitly - to the
binder (fieldtwin.runtime.binder: the Modbus endpoints) and to the PLC's host
(fieldtwin.facade.host: the SCM channels' lines); nothing is chosen by an
ambient setting.  :data:`REAL` opens ptys, serial devices and TCP listeners;
``fieldtwin.transports.virtual.Wiring().backends`` opens their virtual twins.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from fieldtwin.transports.base import LineSettings
from fieldtwin.transports.pty import PtyTransport, open_pty
from fieldtwin.transports.serial import SerialTransport, open_serial
from fieldtwin.transports.tcp import DEFAULT_MAX_CONNECTIONS, TcpListener, listen


@dataclass(frozen=True, slots=True)
class Backends:
    """The openers of the endpoints, by kind."""

    listen: Callable[[str, int, int], TcpListener]  # (host, port, max connections)
    pty: Callable[[LineSettings | None], PtyTransport]
    serial: Callable[[str, LineSettings | None], SerialTransport]  # (device, settings)
    real: bool = True  # False: nothing of the OS is opened (a replay)

    def listener(
        self, host: str, port: int, max_connections: int = DEFAULT_MAX_CONNECTIONS
    ) -> TcpListener:
        return self.listen(host, port, max_connections)


REAL = Backends(listen=listen, pty=open_pty, serial=open_serial)

__all__ = ["REAL", "Backends"]
