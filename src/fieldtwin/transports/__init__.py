"""Thin adapters over the OS: memory pairs, ptys, serial ports, TCP (DESIGN rule 5).

Every backend implements the small ``Transport`` interface of ``base``; the
runner in ``fieldtwin.runtime`` pumps them into the sans-IO device cores.
"""

from fieldtwin.transports.base import (
    AcceptFailed,
    Flushable,
    LineSettings,
    Listener,
    Transport,
    line_settings,
)
from fieldtwin.transports.memory import MemoryTransport, memory_pair
from fieldtwin.transports.pty import PtyTransport, open_pty
from fieldtwin.transports.serial import SerialTransport, open_serial
from fieldtwin.transports.tcp import TcpListener, TcpTransport, connect, listen
from fieldtwin.transports.url import Endpoint, open_endpoint, parse_endpoint

__all__ = [
    "AcceptFailed",
    "Endpoint",
    "Flushable",
    "LineSettings",
    "Listener",
    "MemoryTransport",
    "PtyTransport",
    "SerialTransport",
    "TcpListener",
    "TcpTransport",
    "Transport",
    "connect",
    "line_settings",
    "listen",
    "memory_pair",
    "open_endpoint",
    "open_pty",
    "open_serial",
    "parse_endpoint",
]
