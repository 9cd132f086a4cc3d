"""A made-up device added through the registry alone (docs/architecture.md, worked example).

The "TSX LVL 8" is not a real module: a level sensor card with one analog input
(``"0"``, volts, shown in IWxy,1 in millivolts) and one fault (``float_stuck``,
an application fault that sets IWxy,0,7).  Its core, its adapter and its
registry line are all in this file; nothing outside it changes.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from pathlib import Path
from typing import ClassVar

from fieldtwin.clock import S
from fieldtwin.devices import registry
from fieldtwin.devices.common import apply_faults, apply_inputs
from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import Family, Fault, Input, InputValue, SignalSpec
from fieldtwin.devices.kind import DeviceKind
from fieldtwin.devices.module import IDENTITY, ModuleDevice, insert_module, own_keys
from fieldtwin.devices.schema import Key, Schema, Table
from fieldtwin.errors import ConfigError
from fieldtwin.signals import AnalogSignal, analog_from_spec
from fieldtwin.tsx.module import FaultCategory, IntelligentModule

LEVEL = "TSX LVL 8"
FLOAT_STUCK = 32  # an application fault bit of its fault string
SAMPLE_US = 100_000  # it samples its input every 100 ms


# --- the core (a sans-IO module, as tsx/<kind>/ would hold) ------------------------


class Level(IntelligentModule):
    type_name: ClassVar[str] = LEVEL
    self_test_us: ClassVar[int] = 1 * S
    has_run_stop: ClassVar[bool] = False

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.volts = 0.0
        self.signal: AnalogSignal | None = None

    def on_self_test_done(self, now: int) -> None:
        self.call_later(SAMPLE_US, self._sample)

    def _sample(self, now: int) -> None:
        volts = self.signal.value_at(now) if self.signal is not None else self.volts
        self.iw[1] = max(0, min(0xFFFF, round(volts * 1000)))
        self.call_later(SAMPLE_US, self._sample)

    def fault_category_of(self, bit: int) -> FaultCategory:
        return FaultCategory.APPLICATION


# --- the adapter (as devices/<kind>.py would hold) ----------------------------------


class LevelDevice(ModuleDevice):
    def __init__(self, module: Level, plc: object) -> None:
        super().__init__(module, plc)  # type: ignore[arg-type]
        self.level = module

    def inputs(self) -> Mapping[str, Input]:
        return {"0": Input("0", "analog, volts", self._set, self._drive)}

    def _set(self, value: InputValue) -> None:
        try:
            self.level.volts = float(str(value).removesuffix("V"))
        except ValueError:
            raise ConfigError(f"input 0: {value!r} is not volts (e.g. 2.5V)") from None
        self.level.signal = None

    def _drive(self, spec: SignalSpec, where: str, base_dir: Path | None) -> None:
        self.level.signal = analog_from_spec(spec, where=where, base_dir=base_dir)

    def faults(self) -> Mapping[str, Fault]:
        return {
            "float_stuck": Fault(
                "float_stuck",
                "the float switch is stuck",
                partial(self.level.set_fault, FLOAT_STUCK),
            )
        }

    def configure(self, table: Table, ctx: BuildContext, where: str) -> None:
        inputs = table.get("inputs", {})
        if not isinstance(inputs, Mapping):
            raise ConfigError(f"{where}.inputs: a table of input = value or signal")
        apply_inputs(self, inputs, f"{where}.inputs", ctx.base_dir)
        apply_faults(self, table.get("faults", []), f"{where}.faults")


def build(table: Table, ctx: BuildContext, where: str) -> LevelDevice:
    module, plc = insert_module(table, ctx, where)
    assert isinstance(module, Level)
    device = LevelDevice(module, plc)
    device.configure(own_keys(table), ctx, where)
    return device


SCHEMA = Schema(IDENTITY, (Key("inputs", '{ "0" = volts or signal }'), Key("faults", "names")))

# --- the registry line ----------------------------------------------------------------

registry.register(DeviceKind(LEVEL, Family.MODULE, SCHEMA, build, Level))
