"""The OS behind the Python library's cores: pacing and an SCM channel's real endpoint.

``fieldtwin.hosting`` hands :data:`HOST` to a ``Plc`` built in a script: when a
module wires a pty, a serial device or a TCP listener (``scm.attach(0, "pty")``),
the PLC gets a :class:`~fieldtwin.runtime.runner.Runner` (simulated time then
follows the wall clock) and the channel's line is opened here.
"""

from __future__ import annotations

from collections.abc import Mapping

from fieldtwin.clock import SimClock
from fieldtwin.devices.faults import FaultParam
from fieldtwin.errors import ConfigError
from fieldtwin.facade import faults
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports import parse_endpoint
from fieldtwin.transports.backends import REAL, Backends
from fieldtwin.transports.base import Transport, line_settings
from fieldtwin.transports.tcp import listener_url
from fieldtwin.tsx.bus import Pacer
from fieldtwin.tsx.scm.endpoints import Port
from fieldtwin.tsx.scm.line import Line


class OsHost:
    """Pacing by a Runner; SCM channel lines on ptys, serial devices and TCP, opened
    by ``backends`` (the real ones, or a replay's virtual twins)."""

    def __init__(self, backends: Backends = REAL) -> None:
        self.backends = backends

    def fault_names(self, core: object) -> Mapping[str, str]:
        """The fault names a core's kind takes (``Tes.fault_names()``, docs/tes.md)."""
        return faults.fault_names(core)

    def inject_fault(self, core: object, name: str, on: bool, **params: FaultParam) -> None:
        """A fault by name on a core (``tes.inject_fault("no_answer", True)``)."""
        faults.inject_fault(core, name, on, **params)

    def pacer(self, clock: SimClock, speed: float | None) -> Pacer:
        return Runner(clock, speed)

    def open_line(self, url: str, line: Line, pacer: Pacer) -> Port:
        """Open a pty, serial device or TCP listener for ``line`` and attach it to ``pacer``."""
        if not isinstance(pacer, Runner):
            raise ConfigError("a real endpoint needs the PLC to be paced by a Runner")
        endpoint = parse_endpoint(url)
        # parse_endpoint gives a serial URL default settings: only a query fixes them
        given = endpoint.settings is not None and "?" in url
        port = Port(url, line, runner=pacer, settings_given=given)
        fmt = line.fmt
        settings = endpoint.settings if given else None
        settings = settings or line_settings(
            fmt.baud, fmt.data_bits, fmt.parity.letter, fmt.stop_bits
        )
        if endpoint.scheme == "pty":
            port.peer = self.backends.pty(settings)
            port.path = port.peer.peer_path
            pacer.attach(port.peer, port.feed)
        elif endpoint.scheme == "serial":
            assert endpoint.device is not None
            port.peer = self.backends.serial(endpoint.device, settings)
            port.path = endpoint.device
            pacer.attach(port.peer, port.feed)
        elif endpoint.scheme == "tcp":
            assert endpoint.host is not None and endpoint.port is not None
            port.listener = self.backends.listener(endpoint.host, endpoint.port)
            port.path = listener_url("tcp", port.listener.address)
            pacer.attach_listener(port.listener, lambda t, now: _connected(port, t))
        else:
            raise ConfigError(
                f"endpoint {url!r}: a SCM channel is wired to memory, pty, serial:///DEVICE"
                " or tcp://HOST:PORT (raw characters)"
            )
        return port


def _connected(port: Port, transport: Transport) -> None:
    """A TCP peer connected: it replaces the previous one (one peer per line)."""
    if port.peer is not None:
        port.runner.detach(port.peer)
        port.peer.close()
    port.peer = transport
    port.connections.append(transport.name)
    port.runner.attach(transport, port.feed)


HOST = OsHost()

__all__ = ["HOST", "OsHost"]
