"""Serve TES on their Modbus endpoints from Python (docs/tes.md, "Plant file").

``start_tes_endpoints(tes_list, tables, runner)`` groups the TES by endpoint and
serves each group with the runtime's Modbus server glue; ``build_tes`` reads the
``[[tes]]`` tables.  The older path ``fieldtwin.tes.plant`` still gives both.

``tes_core(device)`` and ``tes_registers(tes)`` let the layers above (the plant's
``plant.tes``, the testing helpers that take a ``Tes``) reach a TES core without
naming the TES packages themselves (docs/architecture.md, "Only the face above
devices/").
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from fieldtwin.devices.face import Device, Objects
from fieldtwin.devices.tes.device import TesDevice, TesRegisters, modbus_slave
from fieldtwin.devices.tes.plantkeys import (
    KEYS,
    build_one,
    build_tes,
    check_lines,
    endpoint_of,
    link_of,
    wire_timing_of,
)
from fieldtwin.endpoint import parse_endpoint
from fieldtwin.modbus.model import Link
from fieldtwin.runtime import modbus_lines
from fieldtwin.runtime.modbus_server import ModbusServer
from fieldtwin.runtime.runner import Runner
from fieldtwin.tes.model import Tes
from fieldtwin.transports.base import LineSettings
from fieldtwin.transports.url import Endpoint


def tes_core(device: Device) -> Tes | None:
    """The TES core behind a device of the plant (None for any other device)."""
    return device.tes if isinstance(device, TesDevice) else None


def tes_registers(tes: Tes) -> Objects:
    """A TES core's words as the face's Objects (by address or by map name)."""
    return TesRegisters(tes)


def line_settings(endpoint: Endpoint, devices: Sequence[Tes], link: Link) -> LineSettings:
    """The line's format: the endpoint's, else the TES's; every TES must agree with it."""
    return modbus_lines.line_settings(endpoint, [modbus_slave(t, link) for t in devices])


def serve_group(
    runner: Runner, endpoint: Endpoint, devices: Sequence[Tes], link: Link
) -> ModbusServer:
    """Serve ``devices`` (TES on one endpoint, reached through the port ``link`` names)."""
    return modbus_lines.serve_group(runner, endpoint, [modbus_slave(t, link) for t in devices])


def start_tes_endpoints(
    tes_list: Sequence[Tes], tables: Sequence[Mapping[str, Any]], runner: Runner
) -> list[ModbusServer]:
    """Group the TES by endpoint and serve each group (``fieldtwin run`` prints describe())."""
    groups: dict[str, list[int]] = {}
    for i, table in enumerate(tables):
        groups.setdefault(str(endpoint_of(table, f"tes[{i}]")), []).append(i)
    servers: list[ModbusServer] = []
    try:
        for url, members in groups.items():
            # build_tes checked that every TES on one endpoint names the same port
            link = link_of(tables[members[0]], f"tes[{members[0]}]")
            servers.append(
                serve_group(runner, parse_endpoint(url), [tes_list[i] for i in members], link)
            )
    except BaseException:
        for server in servers:
            server.close()
        raise
    return servers


__all__ = [
    "KEYS",
    "Tes",
    "build_one",
    "build_tes",
    "check_lines",
    "endpoint_of",
    "line_settings",
    "link_of",
    "serve_group",
    "start_tes_endpoints",
    "tes_core",
    "tes_registers",
    "wire_timing_of",
]
