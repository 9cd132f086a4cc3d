"""Serve the Modbus slaves sharing one endpoint with the Modbus server glue.

What a slave needs of its line (its character format, where a user changes it,
wire timing) comes with its port (fieldtwin.devices.face.ModbusSlave); nothing
here knows a device kind.
"""

from __future__ import annotations

from collections.abc import Sequence

from fieldtwin.devices.face import ModbusSlave
from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import Link
from fieldtwin.runtime.modbus_server import (
    ModbusServer,
    serve_rtu,
    serve_rtu_over_tcp,
    serve_tcp,
)
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.backends import REAL, Backends
from fieldtwin.transports.base import LineSettings
from fieldtwin.transports.url import Endpoint


def line_settings(endpoint: Endpoint, slaves: Sequence[ModbusSlave]) -> LineSettings:
    """The line's format: the endpoint's, else the first slave's; every slave must agree."""
    settings = endpoint.settings or slaves[0].line
    for slave in slaves:
        own = slave.line
        if (own.baud, own.parity) != (settings.baud, settings.parity):
            raise ConfigError(
                f"{slave.name}: endpoint {endpoint} runs at {settings.baud} Bd parity"
                f" {settings.parity.letter}, {slave.what} is set to {own.baud} Bd parity"
                f" {own.parity.letter} ({slave.settings})"
            )
    return settings


def serve_group(
    runner: Runner,
    endpoint: Endpoint,
    slaves: Sequence[ModbusSlave],
    backends: Backends = REAL,
) -> ModbusServer:
    """Serve ``slaves`` (one endpoint, one port of theirs: the plant checked) there, on
    an endpoint ``backends`` opens (real, or a replay's virtual one)."""
    link = slaves[0].link
    devices = [s.slave for s in slaves]
    if endpoint.scheme == "tcp":
        assert endpoint.host is not None and endpoint.port is not None
        # a gateway in front of the RS-232 port uses that port's number, counters, delay
        tcp_link = Link.RS232 if link is Link.RS232 else Link.TCP
        listener = backends.listener(endpoint.host, endpoint.port)
        return serve_tcp(runner, listener, devices, tcp_link)
    settings = line_settings(endpoint, slaves)
    # the plant checked that every slave of one line has the same wire timing
    wire = all(s.wire_timing for s in slaves)
    if endpoint.scheme == "rtu+tcp":
        assert endpoint.host is not None and endpoint.port is not None
        listener = backends.listener(endpoint.host, endpoint.port)
        return serve_rtu_over_tcp(runner, listener, devices, settings, link, wire_timing=wire)
    if endpoint.scheme == "pty":
        # a UART at the TES's settings reads the master's (issue 23); false on any TES: off
        strict = all(s.strict_line for s in slaves)
        what = slaves[0].what.removeprefix("the ")
        pty = backends.pty(settings)
        return serve_rtu(
            runner, pty, devices, link, settings, wire_timing=wire, strict_line=strict, what=what
        )
    if endpoint.scheme == "serial":
        assert endpoint.device is not None
        transport = backends.serial(endpoint.device, settings)
        return serve_rtu(runner, transport, devices, link, settings, wire_timing=wire)
    raise ConfigError(
        f"endpoint {endpoint}: cannot serve Modbus slaves there"
        " (allowed: tcp, rtu+tcp, pty, serial)"
    )
