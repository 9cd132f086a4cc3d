"""What a SCM module's connectors are wired to, and how an operator drives them.

A component the module holds (``ScmModule.wiring``), not a mixin: the ports of
the two channels (memory, pty, serial, TCP), the adaptor input signals
(SCM 5.1), the SCA2 current-loop wiring and the console's ``input`` command.
It reaches the module only through :class:`WiringHost`.
"""

from __future__ import annotations

from typing import Protocol

from fieldtwin.errors import ConfigError
from fieldtwin.tsx.module import ModuleContext
from fieldtwin.tsx.scm.adaptors import Signals
from fieldtwin.tsx.scm.channel import Channel
from fieldtwin.tsx.scm.config import ChannelConfig
from fieldtwin.tsx.scm.endpoints import MemoryPeer, Port
from fieldtwin.tsx.scm.line import Line
from fieldtwin.tsx.scm.variants import Adaptor


class WiringHost(Protocol):
    """What the wiring needs from its module."""

    @property
    def ctx(self) -> ModuleContext: ...

    @property
    def adaptors(self) -> tuple[Adaptor, Adaptor]: ...

    @property
    def lines(self) -> list[Line]: ...

    @property
    def signals(self) -> list[Signals]: ...

    @property
    def channels(self) -> list[Channel]: ...

    @property
    def configs(self) -> list[ChannelConfig | None]: ...

    def changed(self) -> None: ...


class Wiring:
    """The endpoints and the adaptor signals of the two channels of one module."""

    def __init__(self, host: WiringHost) -> None:
        self.host = host
        self.ports: list[Port | None] = [None, None]

    # --- endpoints ------------------------------------------------------------------

    def attach(self, channel: int, endpoint: str) -> MemoryPeer | str:
        """Wire a channel: "memory" returns a MemoryPeer; "pty" the path a peer opens;
        "tcp://127.0.0.1:0" the listening address; "serial:///dev/..." the device."""
        line = self.line(channel)
        self.detach(channel)
        if self.host.adaptors[channel] is Adaptor.NONE:
            raise ConfigError(f"channel {channel} has no adaptor: nothing to wire")
        ctx = self.host.ctx
        if endpoint.strip() == "memory":
            peer = MemoryPeer(ctx.clock, line)
            port = Port("memory", line, peer=peer)
            line.send_port = port.send
            self.ports[channel] = port
            return peer
        if ctx.open_line is None:
            raise ConfigError("a real endpoint needs the module to sit in a Plc (its runner)")
        port = ctx.open_line(endpoint, line)
        assert isinstance(port, Port)
        line.send_port = port.send
        self.ports[channel] = port
        return port.path or port.url

    def detach(self, channel: int) -> None:
        port = self.ports[channel]
        if port is not None:
            port.close()
            self.ports[channel] = None
        self.line(channel).send_port = None

    def follow_configuration(self, channel: int) -> None:
        """A host serial port without settings of its own takes the channel's (SCM 3.2)."""
        port = self.ports[channel]
        config = self.host.configs[channel]
        if port is not None and config is not None:
            port.follow(config.fmt)

    def line(self, channel: int) -> Line:
        if channel not in (0, 1):
            raise ConfigError(f"SCM channel {channel} does not exist (allowed 0 or 1)")
        return self.host.lines[channel]

    def describe(self, channel: int) -> str:
        port = self.ports[channel]
        return port.describe() if port is not None else "not wired"

    # --- adaptor signals (SCM 5.1) ----------------------------------------------------

    def set_signal(self, channel: int, name: str, level: int) -> None:
        """An adaptor input signal (CTS, CD, DSR, RI) as the wiring drives it."""
        self.line(channel)
        self.host.signals[channel].set_input(name, level)
        self._signals_changed(channel)

    def set_loop(self, channel: int, loop: str) -> None:
        """How an SCA2 current loop is wired: "point-to-point" or "multipoint" (SCM 5.1 PSR)."""
        self.line(channel)
        self.host.signals[channel].set_loop(loop)
        self._signals_changed(channel)

    def _signals_changed(self, channel: int) -> None:
        self.host.channels[channel].signals_changed(self.host.ctx.clock.now)
        self.host.changed()
