"""The Device face of the TSX SCM 20xy / 21xy / 22xy (docs/scm.md).

Inputs: ``"0.CTS"``, ``"1.DSR"``... an adaptor input signal at 0 or 1 (SCM 5.1;
the adaptor decides which exist), and ``"0"`` / ``"1"`` for the console's older
channel form ``CTS=0`` or ``loop=point-to-point``.  Ports: a channel wired to a
pty, a serial device or TCP is noted while the plant is built and opened by
the runtime's binder afterwards.  Every SCM-specific call of the face is here.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial

from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import Family, Input, InputValue, Port, PortState
from fieldtwin.devices.kind import Build, DeviceKind
from fieldtwin.devices.module import IDENTITY, ModuleDevice, insert_module, own_keys
from fieldtwin.devices.schema import Key, Schema, Table
from fieldtwin.devices.scm.plantkeys import Wiring, configure_module, signal_text
from fieldtwin.devices.scm.status import details, endpoint_lines
from fieldtwin.errors import ConfigError
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.scm import MODULE_TYPES
from fieldtwin.tsx.scm.adaptors import INPUTS
from fieldtwin.tsx.scm.module import ScmModule

GROUP = "scm"  # a channel's own line: raw characters


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

    def mode(self) -> str | None:
        return None  # SCM 1.2: no Run/Stop mode of its own

    def port_states(self) -> list[PortState]:
        states = []
        for index, port in enumerate(self.scm.ports):
            line = port.describe() if port is not None else "not wired"
            states.append(PortState(f"channel {index}", line))
        return states

    def ports(self) -> list[Port]:
        return [Port(f"channel {ch}", url, GROUP) for ch, url, _ in self.wiring]

    def bind(self, port: Port, runner: object) -> list[str]:
        for ch, url, where in self.wiring:
            if port.name == f"channel {ch}":
                try:
                    self.scm.attach(
                        ch, url
                    )  # ADAPT(SCM): the PLC's host opens it (fieldtwin.facade.host)
                except ConfigError as exc:
                    raise ConfigError(f"{where}: {exc}") from None
                return [line for line in endpoint_lines(self.scm) if f"channel {ch} " in line]
        return super().bind(port, runner)

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
