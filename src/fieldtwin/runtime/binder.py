"""The one endpoint binder: every port of every device is opened here, after the plant is built.

A device lists its ports (:meth:`fieldtwin.devices.face.Device.ports`); a port
belongs to a group that says how it is opened:

* ``modbus`` (a TES): every TES naming the same endpoint shares one line, served
  by the Modbus server glue (fieldtwin.runtime.tes_lines: TCP, RTU over TCP, pty, serial);
* ``scm`` (an SCM channel): the channel's own raw-character line, opened by the
  SCM's endpoint functions (fieldtwin.tsx.scm.endpoints, through the module's
  ``attach``), pumped by the PLC's runner.

Given the plant's event bus, every port opened publishes its traffic on it
(Modbus frames through the server's wiretap, SCM characters through the
channel's port).  ``fieldtwin run`` binds every group; ``load_plant`` (and so the console) binds
the ``scm`` group only, leaving the TES's Modbus endpoints closed.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from functools import partial

from fieldtwin.devices.face import Device, Port
from fieldtwin.devices.scm import GROUP as SERIAL_LINE
from fieldtwin.devices.scm import ScmDevice
from fieldtwin.devices.tes import GROUP as MODBUS
from fieldtwin.devices.tes import TesDevice
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.modbus_server import ModbusServer
from fieldtwin.runtime.runner import Runner
from fieldtwin.runtime.wiretap import CharTap
from fieldtwin.transports.url import parse_endpoint
from fieldtwin.tsx.scm.endpoints import MemoryPeer

ALL = (MODBUS, SERIAL_LINE)


class Binding:
    """What one bind opened: its 'listening: ...' lines, and how to close it."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self._closers: list[Callable[[], None]] = []

    def add(self, lines: Sequence[str], closer: Callable[[], None]) -> None:
        self.lines.extend(lines)
        self._closers.append(closer)

    def close(self) -> None:
        closers, self._closers = self._closers, []
        for close in reversed(closers):
            close()


def bind(
    devices: Sequence[Device],
    runner: Runner | None,
    *,
    groups: Collection[str] = ALL,
    events: EventBus | None = None,
) -> Binding:
    """Open the ports of ``devices`` in ``groups`` (TES groups first, then SCM channels);
    with ``events``, their traffic is published there."""
    binding = Binding()
    try:
        if MODBUS in groups:
            _serve_modbus(devices, runner, binding, events)
        if SERIAL_LINE in groups:
            _attach_channels(devices, binding, events)
            if events is not None:  # the modules' group: bound once per plant
                _tap_streams(devices, binding, events)
    except BaseException:
        binding.close()
        raise
    return binding


def _serve_modbus(
    devices: Sequence[Device], runner: Runner | None, binding: Binding, events: EventBus | None
) -> None:
    from fieldtwin.runtime.tes_lines import serve_group

    lines: dict[str, list[TesDevice]] = {}
    for device in devices:
        if isinstance(device, TesDevice):
            for port in device.ports():
                lines.setdefault(port.endpoint, []).append(device)
    if lines and runner is None:
        raise ConfigError("a TES endpoint needs the real-time runner (fieldtwin run)")
    for url, members in lines.items():
        assert runner is not None
        # the plant builder checked that every TES on one endpoint names the same port
        server: ModbusServer = serve_group(
            runner, parse_endpoint(url), [d.tes for d in members], members[0].link
        )
        if events is not None:
            server.tap(events, url)
        binding.add([server.describe()], server.close)
        if server.kind != "modbus-rtu":  # a TCP endpoint: the drop_connections fault
            for member in members:
                droppers = member.tes.line_faults.droppers
                droppers.append(server.drop_connections)
                binding.add([], partial(droppers.remove, server.drop_connections))


def _attach_channels(devices: Sequence[Device], binding: Binding, events: EventBus | None) -> None:
    for device in devices:
        if not isinstance(device, ScmDevice):
            continue
        for port in device.ports():
            binding.add(device.bind(port, None), _detacher(device, port))
        if events is not None:
            _tap_channels(device, events)


def _tap_channels(device: ScmDevice, events: EventBus) -> None:
    """Every wired channel (memory ones were wired when the module was built)."""
    for channel, wired in enumerate(device.scm.ports):
        if wired is None:
            continue
        clock = device.scm.ctx.clock
        tap = CharTap(events, clock, str(device.address), channel, wired.url.split("?")[0])
        wired.tap = tap
        if isinstance(wired.peer, MemoryPeer):
            wired.peer.tap = tap


def _tap_streams(devices: Sequence[Device], binding: Binding, events: EventBus) -> None:
    """Every stream a device's face offers (a DEM's messages...) is published on the bus."""
    for device in devices:
        source = str(device.address)
        for stream in device.streams():
            stop = stream.subscribe(partial(_publish, events, stream.kind, source))
            binding.add([], stop)


def _publish(
    events: EventBus, kind: str, source: str, now: int, data: Mapping[str, object]
) -> None:
    if events.active:
        events.publish(now, kind, source, dict(data))


def _detacher(device: ScmDevice, port: Port) -> Callable[[], None]:
    channel = int(port.name.split()[-1])
    return lambda: device.scm.detach(channel)


__all__ = ["ALL", "MODBUS", "SERIAL_LINE", "Binding", "bind"]
