"""Serve a group of TES sharing one endpoint with the Modbus server glue."""

from __future__ import annotations

from collections.abc import Sequence

from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import Link
from fieldtwin.runtime.modbus_server import (
    ModbusServer,
    serve_rtu,
    serve_rtu_over_tcp,
    serve_tcp,
)
from fieldtwin.runtime.runner import Runner
from fieldtwin.tes.model import Tes
from fieldtwin.tes.state import link_key
from fieldtwin.transports.base import LineSettings
from fieldtwin.transports.base import line_settings as char_format
from fieldtwin.transports.pty import open_pty
from fieldtwin.transports.serial import open_serial
from fieldtwin.transports.tcp import listen
from fieldtwin.transports.url import Endpoint


def tes_line_settings(tes: Tes, link: Link) -> LineSettings:
    """§3.1.3: speed and parity are parameters; 8 data bits and 1 stop bit are fixed."""
    key = link_key(link)
    baud, parity = tes.params[f"{key}.baud"], tes.params[f"{key}.parity"]
    assert isinstance(baud, int) and isinstance(parity, str)
    return char_format(baud=baud, data_bits=8, parity=parity, stop_bits=1)


def line_settings(endpoint: Endpoint, devices: Sequence[Tes], link: Link) -> LineSettings:
    """The line's format: the endpoint's, else the TES's; every TES must agree with it."""
    settings = endpoint.settings or tes_line_settings(devices[0], link)
    for tes in devices:
        own = tes_line_settings(tes, link)
        if (own.baud, own.parity) != (settings.baud, settings.parity):
            key = link_key(link)
            raise ConfigError(
                f"{tes.name}: endpoint {endpoint} runs at {settings.baud} Bd parity"
                f" {settings.parity.letter}, the TES is set to {own.baud} Bd parity"
                f" {own.parity.letter}"
                f" ({key}.baud / {key}.parity; change them with `fieldtwin tesis`)"
            )
    return settings


def serve_group(
    runner: Runner, endpoint: Endpoint, devices: Sequence[Tes], link: Link
) -> ModbusServer:
    if endpoint.scheme == "tcp":
        assert endpoint.host is not None and endpoint.port is not None
        # a gateway in front of the RS-232 port uses that port's number, counters, delay
        tcp_link = Link.RS232 if link is Link.RS232 else Link.TCP
        return serve_tcp(runner, listen(endpoint.host, endpoint.port), devices, tcp_link)
    settings = line_settings(endpoint, devices, link)
    # the plant checked that every TES of one line has the same ``wire_timing``
    wire = all(tes.wire_timing for tes in devices)
    if endpoint.scheme == "rtu+tcp":
        assert endpoint.host is not None and endpoint.port is not None
        listener = listen(endpoint.host, endpoint.port)
        return serve_rtu_over_tcp(runner, listener, devices, settings, link, wire_timing=wire)
    if endpoint.scheme == "pty":
        return serve_rtu(runner, open_pty(settings), devices, link, settings, wire_timing=wire)
    if endpoint.scheme == "serial":
        assert endpoint.device is not None
        transport = open_serial(endpoint.device, settings)
        return serve_rtu(runner, transport, devices, link, settings, wire_timing=wire)
    raise ConfigError(
        f"endpoint {endpoint}: cannot serve TES there (allowed: tcp, rtu+tcp, pty, serial)"
    )
