"""The Device face of the TSX DEM 2412 / 2413 (docs/dem24.md).

Inputs ``"0"``..``"23"``: a contact (true/false, 1/0, on/off) or volts judged as
IEC 61131-2 type 1 (``18.5``, ``"18.5V"``); a signal spec drives it.  The sync
output ``sync = { from_slot }`` is wired through the PLC once every module of
the plant is in (the build context), not through a process-wide table.
Every DEM-specific call of the face is in this file.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from functools import partial
from pathlib import Path

from fieldtwin.devices.common import apply_faults, apply_inputs
from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.dem24.plantkeys import configure, console_value
from fieldtwin.devices.dem24.status import details
from fieldtwin.devices.face import (
    Family,
    FrontPanel,
    Input,
    InputValue,
    Logged,
    Publish,
    SignalSpec,
    Stream,
)
from fieldtwin.devices.kind import Build, DeviceKind
from fieldtwin.devices.module import IDENTITY, ModuleDevice, insert_module, own_keys
from fieldtwin.devices.schema import Key, Schema, Table
from fieldtwin.errors import ConfigError
from fieldtwin.signals import signal_from_spec
from fieldtwin.tsx.dem24.inputs import CHANNELS
from fieldtwin.tsx.dem24.models import Dem24, Dem2412, Dem2413
from fieldtwin.tsx.dem24.stack import Message, MessageType
from fieldtwin.tsx.plc import Plc

KIND_DEM = "dem"  # the event kind of a DEM's messages (docs/control.md, "Events")
LOG_SHOWN = 8  # the newest stacked messages its front shows (DEM 4.2-2 layout)


class Dem24Device(ModuleDevice):
    def __init__(self, module: Dem24, plc: Plc) -> None:
        super().__init__(module, plc)
        self.dem = module

    def streams(self) -> Sequence[Stream]:
        """Each message as the DEM logs it (or loses it, stack full), with its stamp."""
        return (Stream(KIND_DEM, "messages logged, with their time stamps", self._subscribe),)

    def _subscribe(self, publish: Publish) -> Callable[[], None]:
        logbook = self.dem.logbook
        clock = self.dem.clock

        def tap(message: Message, stored: bool, flagged: bool, fill: int) -> None:
            publish(clock.now, message_data(message, stored, flagged, fill))

        logbook.tap = tap
        return partial(setattr, logbook, "tap", None)

    def panel(self) -> FrontPanel:
        """The module's time, its stack (fill, size, overflow, the newest messages) and
        its logging, looked at: nothing is unstacked."""
        dem = self.dem
        lines = {**dem.status(), **details(dem)}
        stack = dem.stack
        fields = (
            ("time", lines.get("time", "")),
            ("stack", lines.get("stack", "")),
            ("fill", len(stack)),
            ("size", stack.size),
            ("overflow", stack.total_lost > 0 or stack.lost > 0),
            ("lost", stack.total_lost),
            ("logging", lines.get("logging", "")),
            ("sync_fault", lines.get("sync fault", "")),
        )
        log = tuple(logged(m) for m in reversed(stack.peek()[-LOG_SHOWN:]))
        return FrontPanel(self.leds(), fields=fields, log=log)

    def inputs(self) -> Mapping[str, Input]:
        return {
            str(ch): Input(
                str(ch),
                "contact: 1/0, on/off, or volts (18.5V)",
                partial(self._set, ch),
                partial(self._drive, ch),
            )
            for ch in range(CHANNELS)
        }

    def _set(self, channel: int, value: InputValue) -> None:
        self.dem.set_input(channel, console_value(value) if isinstance(value, str) else value)

    def _drive(self, channel: int, spec: SignalSpec, where: str, base: Path | None) -> None:
        self.dem.set_signal(channel, signal_from_spec(spec, where=where, base_dir=base))

    def details(self) -> dict[str, str]:
        return details(self.dem)

    def configure(self, table: Table, ctx: BuildContext, where: str) -> None:
        rest = dict(table)
        if "inputs" in rest:
            spec = rest.pop("inputs")
            if not isinstance(spec, Mapping):
                raise ConfigError(f"{where}.inputs: must be a table of channel = value or signal")
            apply_inputs(self, spec, f"{where}.inputs", ctx.base_dir)
        faults = rest.pop("faults", [])
        configure(self.dem, rest, where, ctx.base_dir, lambda r, s: self._follow(ctx, r, s, where))
        apply_faults(self, faults, f"{where}.faults")

    def _follow(self, ctx: BuildContext, rack: int, slot: int, where: str) -> None:
        """``sync = { from_rack, from_slot }``: that module's OUT-SYN drives this IN-SYN."""
        plc = ctx.require_plc(where)

        def wire() -> None:
            try:
                source = plc.module(rack, slot)
            except ConfigError as exc:
                raise ConfigError(f"{where}.sync.from_slot: {exc}") from None
            if not isinstance(source, Dem24):
                raise ConfigError(
                    f"{where}.sync.from_slot: rack {rack} slot {slot} holds a"
                    f" {source.type_name}, not a time-stamping module"
                )
            try:
                source.connect_sync_output(self.dem)
            except ConfigError as exc:
                raise ConfigError(f"{where}.sync: {exc}") from None

        ctx.after_build(wire)


SCHEMA = Schema(
    IDENTITY,
    (
        Key("inputs", 'a table: channel = value or signal, e.g. { "0" = true, "3" = 24.0 }'),
        Key("sync", "{ period_s, start_s } a pulse source, or { from_rack, from_slot }"),
        Key("time", 'the time sent after the first self-test, "1994-07-15T18:05:33"'),
        Key("time_indicator", "0..255, with time"),
        Key("config", "the 9 configuration words, sent after the first self-test"),
        Key("clock_drift_ppm", "the module clock's drift"),
        Key("faults", "fault names set at start"),
    ),
)


def _builder(cls: type[Dem24]) -> Build:
    def build(table: Table, ctx: BuildContext, where: str) -> Dem24Device:
        module, plc = insert_module(table, ctx, where)
        assert isinstance(module, cls)
        device = Dem24Device(module, plc)
        device.configure(own_keys(table), ctx, where)
        return device

    return build


KINDS = tuple(
    DeviceKind(cls.type_name, Family.MODULE, SCHEMA, _builder(cls), cls)
    for cls in (Dem2412, Dem2413)
)


def message_text(message: Message) -> str:
    """``input 3 -> 1``, ``overall inputs H'00A0F1'``: the message as people read it."""
    if message.type is MessageType.CHANGE:
        return f"input {message.channel} -> {message.state}"
    states = message.body[4] | ((message.body[5] & 0xFF) << 16)
    return f"overall inputs H'{states:06X}'"


def logged(message: Message) -> Logged:
    kind = "change" if message.type is MessageType.CHANGE else "overall"
    return Logged(str(message.stamp), kind, message_text(message), ("H",) if message.h else ())


def message_data(message: Message, stored: bool, flagged: bool, fill: int) -> dict[str, object]:
    """A DEM message as its event carries it (DEM 4.2-2: the stamp, the change or the words)."""
    change = message.type is MessageType.CHANGE
    data: dict[str, object] = {
        "type": "change" if change else "overall",
        "stamp": str(message.stamp),
        "h": message.h,
        "indicator": message.indicator,
        "stored": stored,
        "overflow": flagged,
        "stack": fill,
    }
    if change:
        data["channel"], data["state"] = message.channel, message.state
    else:
        data["words"] = [f"{w:04X}" for w in message.body]
    return data
