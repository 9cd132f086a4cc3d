"""What a SCM module's connectors are wired to, and how an operator sees and drives them.

A mixin of :class:`~fieldtwin.tsx.scm.module.ScmModule`: endpoints (memory, pty,
serial, TCP), the adaptor input signals (SCM 5.1), the SCA2 current-loop wiring,
the console's ``input`` command and the status lines.
"""

from __future__ import annotations

from typing import Any, ClassVar

from fieldtwin.errors import ConfigError
from fieldtwin.tsx.module import ModuleContext
from fieldtwin.tsx.scm.adaptors import Signals
from fieldtwin.tsx.scm.channel import Channel
from fieldtwin.tsx.scm.config import ChannelConfig
from fieldtwin.tsx.scm.endpoints import MemoryPeer, Port, open_real
from fieldtwin.tsx.scm.line import CharFormat, Line
from fieldtwin.tsx.scm.variants import Adaptor


class ScmWiring:
    """Endpoints, signals, console and status of the two channels."""

    # provided by ScmModule / IntelligentModule
    type_name: ClassVar[str]
    ctx: ModuleContext
    rack: int
    slot: int
    app_name: bytes
    adaptors: tuple[Adaptor, Adaptor]
    lines: list[Line]
    signals: list[Signals]
    channels: list[Channel]
    configs: list[ChannelConfig | None]
    ports: list[Port | None]

    def changed(self) -> None:
        raise NotImplementedError

    # --- endpoints ------------------------------------------------------------------

    def attach(self, channel: int, endpoint: str) -> Any:
        """Wire a channel: "memory" returns a MemoryPeer; "pty" the path a peer opens;
        "tcp://127.0.0.1:0" the listening address; "serial:///dev/..." the device."""
        line = self._line(channel)
        self.detach(channel)
        if self.adaptors[channel] is Adaptor.NONE:
            raise ConfigError(f"channel {channel} has no adaptor: nothing to wire")
        if endpoint.strip() == "memory":
            port = Port("memory", line)
            port.peer = MemoryPeer(self.ctx.clock, line.feed)
            line.send_port = port.send
            self.ports[channel] = port
            return port.peer
        if self.ctx.pace is None:
            raise ConfigError("a real endpoint needs the module to sit in a Plc (its runner)")
        port = open_real(endpoint, line, self.ctx.pace())
        line.send_port = port.send
        self.ports[channel] = port
        return port.path

    def attach_memory(self, channel: int) -> MemoryPeer:
        peer = self.attach(channel, "memory")
        assert isinstance(peer, MemoryPeer)
        return peer

    def detach(self, channel: int) -> None:
        port = self.ports[channel]
        if port is not None:
            port.close()
            self.ports[channel] = None
        self._line(channel).send_port = None

    def follow_configuration(self, channel: int) -> None:
        """A host serial port without settings of its own takes the channel's (SCM 3.2)."""
        port = self.ports[channel]
        config = self.configs[channel]
        if port is not None and config is not None:
            port.follow(config.fmt, config.baud)

    def _line(self, channel: int) -> Line:
        if channel not in (0, 1):
            raise ConfigError(f"SCM channel {channel} does not exist (allowed 0 or 1)")
        return self.lines[channel]

    def peer_format(self, channel: int) -> CharFormat:
        return self._line(channel).fmt

    # --- adaptor signals (SCM 5.1) ----------------------------------------------------

    def set_signal(self, channel: int, name: str, level: int) -> None:
        """An adaptor input signal (CTS, CD, DSR, RI) as the wiring drives it."""
        self._line(channel)
        self.signals[channel].set_input(name, level)
        self.channels[channel].signals_changed(self.ctx.clock.now)
        self.changed()

    def set_loop(self, channel: int, loop: str) -> None:
        """How an SCA2 current loop is wired: "point-to-point" or "multipoint" (SCM 5.1 PSR)."""
        self._line(channel)
        self.signals[channel].set_loop(loop)
        self.channels[channel].signals_changed(self.ctx.clock.now)
        self.changed()

    def console_input(self, channel: int, text: str) -> None:
        name, sep, level = text.partition("=")
        if sep and name.strip().lower() == "loop":
            self.set_loop(channel, level)
            return
        if not sep or level.strip() not in ("0", "1"):
            raise ConfigError(
                f"SCM input {text!r}: write SIGNAL=0 or SIGNAL=1 (e.g. CTS=0),"
                " or loop=point-to-point / loop=multipoint (SCA2)"
            )
        self.set_signal(channel, name, int(level))

    # --- status ---------------------------------------------------------------------

    def endpoint_lines(self) -> list[str]:
        """One line per channel wired to a real endpoint, for `fieldtwin run`."""
        address = f"{self.slot}" if self.rack == 0 else f"{self.rack}{self.slot}"
        lines = []
        for index, port in enumerate(self.ports):
            if port is not None and port.url != "memory":
                lines.append(
                    f"listening: {self.type_name} slot {address} channel {index} {port.describe()}"
                )
        return lines

    def status_details(self) -> dict[str, str]:
        lines = {}
        for index, channel in enumerate(self.channels):
            port = self.ports[index]
            wiring = port.describe() if port is not None else "not wired"
            lines[f"channel {index}"] = (
                f"{self.adaptors[index].label} | {channel.describe()} | {wiring}"
                f" | {self.signals[index].describe()}"
            )
        if self.app_name:
            lines["application name"] = self.app_name.decode("latin-1").rstrip()
        return lines
