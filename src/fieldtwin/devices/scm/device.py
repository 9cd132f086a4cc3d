"""The Device face of the TSX SCM 20xy / 21xy / 22xy (docs/scm.md).

Inputs: ``"0.CTS"``, ``"1.DSR"``... an adaptor input signal at 0 or 1 (SCM 5.1;
the adaptor decides which exist), and ``"0"`` / ``"1"`` for the console's older
channel form ``CTS=0`` or ``loop=point-to-point``.  Ports: a channel wired to a
pty, a serial device or TCP is noted while the plant is built and opened by
the runtime's binder afterwards.  Every SCM-specific call of the face is here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from functools import partial

from fieldtwin.devices.chars import KIND_SERIAL, CharBlocks
from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import (
    OWN_LINE,
    Family,
    FrontPanel,
    Input,
    InputValue,
    Opened,
    Port,
    PortKind,
    PortState,
    Publish,
    Reading,
    Stream,
    watching,
)
from fieldtwin.devices.kind import Build, DeviceKind
from fieldtwin.devices.module import IDENTITY, ModuleDevice, insert_module, own_keys
from fieldtwin.devices.schema import Key, Schema, Table
from fieldtwin.devices.scm.plantkeys import Wiring, configure_module, signal_text
from fieldtwin.devices.scm.status import details, endpoint_lines
from fieldtwin.errors import ConfigError
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.scm import MODULE_TYPES
from fieldtwin.tsx.scm.adaptors import INPUTS
from fieldtwin.tsx.scm.endpoints import MemoryPeer
from fieldtwin.tsx.scm.module import ScmModule

GROUP = OWN_LINE  # a channel's own line: raw characters, opened by the channel
SCM_CHANNEL = PortKind("SCM channel")  # raw characters: no Modbus line fault applies


class ScmDevice(ModuleDevice):
    def __init__(self, module: ScmModule, plc: Plc) -> None:
        super().__init__(module, plc)
        self.scm = module
        self.wiring: Wiring = []

    def inputs(self) -> Mapping[str, Input]:
        found: dict[str, Input] = {}
        for ch in (0, 1):
            found[str(ch)] = Input(
                str(ch), "SIGNAL=0|1 or loop=point-to-point|multipoint", partial(self._text, ch)
            )
            for name in INPUTS[self.scm.adaptors[ch]]:
                if name != "PSR":
                    key = f"{ch}.{name}"
                    found[key] = Input(key, "signal level 0 or 1", partial(self._level, ch, name))
        return found

    def input(self, name: str) -> Input:
        channel, dot, signal = name.strip().partition(".")
        return super().input(f"{channel}.{signal.upper()}" if dot else channel)

    def _text(self, channel: int, value: InputValue) -> None:
        signal_text(self.scm, channel, str(value))

    def _level(self, channel: int, name: str, value: InputValue) -> None:
        level = {"0": 0, "1": 1, "0.0": 0, "1.0": 1, "false": 0, "true": 1}.get(str(value).lower())
        if level is None:
            raise ConfigError(f"{name}: {value!r} not allowed (allowed 0 or 1)")
        self.scm.set_signal(channel, name, level)

    def panel(self) -> FrontPanel:
        """Its activity and each channel's line as the status shows them."""
        lines = {**self.scm.status(), **details(self.scm)}
        channels = tuple(
            Reading(str(ch), None, text=lines.get(f"channel {ch}", "")) for ch in (0, 1)
        )
        return FrontPanel(
            self.leds(), readings=channels, fields=(("activity", lines.get("activity", "")),)
        )

    def streams(self) -> Sequence[Stream]:
        """The characters of every wired channel, in and out, in blocks (docs/trace.md)."""
        return (Stream(KIND_SERIAL, "characters in and out of each wired channel", self._watch),)

    def _watch(self, publish: Publish) -> Callable[[], None]:
        """Every channel wired now (memory ones were wired when the module was built)."""
        scm = self.scm
        taps = []
        for channel, wired in enumerate(scm.ports):
            if wired is None:
                continue
            line = wired.url.split("?")[0]
            tap = CharBlocks(scm.ctx.clock, channel, line, publish, watching(publish))
            wired.tap = tap
            if isinstance(wired.peer, MemoryPeer):
                wired.peer.tap = tap
            taps.append((wired, tap))

        def stop() -> None:
            for wired, tap in taps:
                if wired.tap is tap:
                    wired.tap = None
                if isinstance(wired.peer, MemoryPeer) and wired.peer.tap is tap:
                    wired.peer.tap = None

        return stop

    def mode(self) -> str | None:
        return None  # SCM 1.2: no Run/Stop mode of its own

    def port_states(self) -> list[PortState]:
        states = []
        for index, port in enumerate(self.scm.ports):
            line = port.describe() if port is not None else "not wired"
            states.append(PortState(f"channel {index}", line))
        return states

    def ports(self) -> list[Port]:
        return [
            Port(
                f"channel {ch}",
                url,
                GROUP,
                SCM_CHANNEL,
                opener=partial(self._open, ch, url, where),
            )
            for ch, url, where in self.wiring
        ]

    def _open(self, ch: int, url: str, where: str) -> Opened:
        try:
            self.scm.attach(ch, url)  # ADAPT(SCM): the PLC's host opens it (fieldtwin.facade.host)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None
        lines = tuple(line for line in endpoint_lines(self.scm) if f"channel {ch} " in line)
        return Opened(lines, partial(self.scm.detach, ch))

    def details(self) -> dict[str, str]:
        return details(self.scm)

    def configure(self, table: Table, ctx: BuildContext, where: str) -> None:
        configure_module(self.scm, table, where, self.wiring)


SCHEMA = Schema(
    IDENTITY,
    (
        Key("adaptors", "the two line adaptors, overriding appendix 7.3"),
        Key("faults", "fault names set at start"),
        Key("channels", "[{ channel, endpoint, config, signals, loop }]"),
    ),
)


def _builder() -> Build:
    def build(table: Table, ctx: BuildContext, where: str) -> ScmDevice:
        module, plc = insert_module(table, ctx, where)
        assert isinstance(module, ScmModule)
        device = ScmDevice(module, plc)
        device.configure(own_keys(table), ctx, where)
        return device

    return build


KINDS = tuple(
    DeviceKind(name, Family.MODULE, SCHEMA, _builder(), cls) for name, cls in MODULE_TYPES.items()
)
