"""The one endpoint binder: every port of every device is opened here, after the plant is built.

A device lists its ports (:meth:`fieldtwin.devices.face.Device.ports`); a port's
group says how the runtime opens it, and the port carries what that takes
(docs/architecture.md, "Ports by kind"):

* ``modbus`` (SHARED_MODBUS): every port naming the same endpoint shares one
  line, served by the Modbus server glue (fieldtwin.runtime.modbus_lines: TCP,
  RTU over TCP, pty, serial); each port gives its slave (``Port.modbus``);
* ``scm`` (OWN_LINE): a port that opens its own line (an SCM channel's raw
  characters, pumped by the PLC's runner) through ``Port.opener``.

A group without an opener here is the device's own business (a made-up device's
loop): the binder leaves it alone.  Given the plant's event bus, every Modbus
endpoint opened publishes its frames on it (the server's wiretap), and every
stream a device offers (:meth:`~fieldtwin.devices.face.Device.streams`: a DEM's
messages, an SCM's characters) is published there.  ``fieldtwin run`` binds every
group; ``load_plant`` (and so the console) binds the ``scm`` group only, leaving
the Modbus endpoints closed.  Nothing here knows a device kind.

The shared Modbus endpoints are opened by the ``backends`` given (the real ones by
default; a replay gives virtual ones, fieldtwin.transports.virtual); a port that
opens its own line does so through its device, whose PLC's host holds the same
choice (``build_plant(host=...)``).
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from functools import partial

from fieldtwin.devices.face import OWN_LINE, SHARED_MODBUS, Device, ModbusSlave
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.modbus_server import ModbusServer
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.backends import REAL, Backends
from fieldtwin.transports.url import parse_endpoint

MODBUS = SHARED_MODBUS
SERIAL_LINE = OWN_LINE
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


Opener = Callable[[Sequence[Device], "Runner | None", Binding, "EventBus | None", Backends], None]


def bind(
    devices: Sequence[Device],
    runner: Runner | None,
    *,
    groups: Collection[str] = ALL,
    events: EventBus | None = None,
    backends: Backends = REAL,
) -> Binding:
    """Open the ports of ``devices`` in ``groups`` (shared Modbus endpoints first, then
    the ports that open their own line) with ``backends``; with ``events``, their
    traffic is published there."""
    binding = Binding()
    try:
        for group, opener in OPENERS.items():
            if group in groups:
                opener(devices, runner, binding, events, backends)
        if SERIAL_LINE in groups and events is not None:  # once per plant, after the lines
            _tap_streams(devices, binding, events)
    except BaseException:
        binding.close()
        raise
    return binding


def _serve_modbus(
    devices: Sequence[Device],
    runner: Runner | None,
    binding: Binding,
    events: EventBus | None,
    backends: Backends,
) -> None:
    from fieldtwin.runtime.modbus_lines import serve_group

    lines: dict[str, list[ModbusSlave]] = {}
    for device in devices:
        for port in device.ports():
            if port.group == MODBUS and port.modbus is not None:
                lines.setdefault(port.endpoint, []).append(port.modbus)
    if lines and runner is None:
        raise ConfigError("a Modbus endpoint needs the real-time runner (fieldtwin run)")
    for url, members in lines.items():
        assert runner is not None
        # the plant builder checked that every slave on one endpoint names the same port
        server: ModbusServer = serve_group(runner, parse_endpoint(url), members, backends)
        if events is not None:
            server.tap(events, url)
        binding.add([server.describe()], server.close)
        if server.kind != "modbus-rtu":  # a TCP endpoint: the drop_connections fault
            for member in members:
                if member.drop_connections is not None:
                    member.drop_connections(server.drop_connections)
                    binding.add([], partial(member.drop_connections, None))


def _open_own_lines(
    devices: Sequence[Device],
    runner: Runner | None,
    binding: Binding,
    events: EventBus | None,
    backends: Backends,
) -> None:
    for device in devices:
        for port in device.ports():
            if port.group == SERIAL_LINE and port.opener is not None:
                opened = port.opener()
                binding.add(opened.lines, opened.close)


OPENERS: dict[str, Opener] = {MODBUS: _serve_modbus, SERIAL_LINE: _open_own_lines}


def _tap_streams(devices: Sequence[Device], binding: Binding, events: EventBus) -> None:
    """Every stream a device's face offers (a DEM's messages, an SCM's characters...)
    is published on the bus."""
    for device in devices:
        source = str(device.address)
        for stream in device.streams():
            stop = stream.subscribe(_Publisher(events, stream.kind, source))
            binding.add([], stop)


class _Publisher:
    """``publish(now, data)`` onto the bus, and whether anyone looks (``active``)."""

    def __init__(self, events: EventBus, kind: str, source: str) -> None:
        self._events = events
        self._kind = kind
        self._source = source

    @property
    def active(self) -> bool:
        return self._events.active

    def __call__(self, now: int, data: Mapping[str, object]) -> None:
        if self._events.active:
            self._events.publish(now, self._kind, self._source, dict(data))


__all__ = ["ALL", "MODBUS", "OPENERS", "SERIAL_LINE", "Binding", "bind"]
