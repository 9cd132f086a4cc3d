"""The Device face of the TSX AEM 811 (docs/aem811.md).

Inputs ``"0"``..``"7"``: a channel's electrical value, ``"2.5V"``, ``"12mA"``,
``"open"`` or a number in the unit of the channel's range; a signal spec drives
it in that unit.  Every AEM-specific call of the face is in this file.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from pathlib import Path

from fieldtwin.devices.aem811.plantkeys import read_plant_table
from fieldtwin.devices.aem811.status import channel_flags, details, threshold_bits
from fieldtwin.devices.aem811.values import set_value
from fieldtwin.devices.common import apply_faults, apply_inputs
from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import Family, FrontPanel, Input, InputValue, Reading, SignalSpec
from fieldtwin.devices.kind import DeviceKind
from fieldtwin.devices.module import IDENTITY, ModuleDevice, insert_module, own_keys
from fieldtwin.devices.schema import Key, Schema, Table
from fieldtwin.signals.spec import analog_from_spec
from fieldtwin.tsx.aem811.module import Aem811
from fieldtwin.tsx.plc import Plc

CHANNELS = range(8)


class Aem811Device(ModuleDevice):
    def __init__(self, module: Aem811, plc: Plc) -> None:
        super().__init__(module, plc)
        self.aem = module

    def inputs(self) -> Mapping[str, Input]:
        return {
            str(ch): Input(
                str(ch),
                "analog: 2.5V, 12mA, open, or a number in the range's unit",
                partial(self._set, ch),
                partial(self._drive, ch),
            )
            for ch in CHANNELS
        }

    def _set(self, channel: int, value: InputValue) -> None:
        set_value(self.aem, channel, value)

    def _drive(self, channel: int, spec: SignalSpec, where: str, base: Path | None) -> None:
        self.aem.set_signal(channel, analog_from_spec(spec, where=where, base_dir=base))

    def panel(self) -> FrontPanel:
        """Each channel's measurement in its configured scaling, its range, its threshold
        bits and its channel faults (AEM 4.2, 5.1), beside the status line."""
        aem = self.aem
        lines = {**aem.status(), **details(aem)}
        readings = []
        for ch, cfg in enumerate(aem.config.channels):
            enabled = bool(aem.enabled >> ch & 1)
            m = aem.measurements[ch]
            flags = channel_flags(m)
            bits = threshold_bits(aem, ch)
            more: tuple[tuple[str, str | bool], ...] = (
                ("range", cfg.range.name),
                ("sqrt", cfg.sqrt),
                ("threshold_bits", bits),
            )
            value = aem.values[ch] if enabled else None
            text = lines.get(f"channel {ch}", "")
            readings.append(Reading(str(ch), value, "", flags, text, more))
        fields = tuple((k, v) for k, v in lines.items() if not k.startswith("channel "))
        return FrontPanel(self.leds(), readings=tuple(readings), fields=fields)

    def details(self) -> dict[str, str]:
        return details(self.aem)

    def configure(self, table: Table, ctx: BuildContext, where: str) -> None:
        rest = dict(table)
        if isinstance(rest.get("inputs"), Mapping):
            apply_inputs(self, rest.pop("inputs"), f"{where}.inputs", ctx.base_dir)  # type: ignore[arg-type]
        if "faults" in rest:
            apply_faults(self, rest.pop("faults"), f"{where}.faults")
        read_plant_table(self.aem, rest, where, ctx.base_dir)


SCHEMA = Schema(
    IDENTITY,
    (
        Key("quantize", "true: values as the 12-bit converter gives them"),
        Key("inputs", "a list of { channel, volts | milliamps | open_circuit }, or a table"),
        Key("faults", "fault names set at start"),
        Key("config", "{ period, channels = [...] }: the configuration sent after self-test"),
        Key("config_words", "the configuration as words"),
        Key("threshold0", "8 level-0 thresholds"),
        Key("threshold1", "8 level-1 thresholds"),
    ),
)


def build(table: Table, ctx: BuildContext, where: str) -> Aem811Device:
    module, plc = insert_module(table, ctx, where)
    assert isinstance(module, Aem811)
    device = Aem811Device(module, plc)
    device.configure(own_keys(table), ctx, where)
    return device


KINDS = (DeviceKind("TSX AEM 811", Family.MODULE, SCHEMA, build, Aem811),)
