"""Endpoint URLs (parsed by ``fieldtwin.endpoint``) opened as transports and listeners."""

from __future__ import annotations

from fieldtwin.endpoint import FORMS, LINE_KEYS, SCHEMES, Endpoint, parse_endpoint
from fieldtwin.errors import ConfigError
from fieldtwin.transports.base import Listener, Transport, line_settings
from fieldtwin.transports.pty import open_pty
from fieldtwin.transports.serial import open_serial
from fieldtwin.transports.tcp import listen


def open_endpoint(endpoint: Endpoint) -> Transport | Listener:
    """Open the twin's side of ``endpoint``: a pty, a serial port, or a TCP listener.

    A memory endpoint has no side of its own: the code that wants one makes a
    ``memory_pair()`` and keeps both ends.
    """
    if endpoint.scheme == "pty":
        return open_pty(endpoint.settings)
    if endpoint.scheme == "serial":
        assert endpoint.device is not None
        return open_serial(endpoint.device, endpoint.settings or line_settings())
    if endpoint.is_tcp:
        assert endpoint.host is not None and endpoint.port is not None
        return listen(endpoint.host, endpoint.port)
    raise ConfigError(f"endpoint {str(endpoint)!r} cannot be opened alone; use memory_pair()")


__all__ = ["FORMS", "LINE_KEYS", "SCHEMES", "Endpoint", "open_endpoint", "parse_endpoint"]
