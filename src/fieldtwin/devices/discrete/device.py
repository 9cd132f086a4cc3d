"""The Device face of the plain discrete input and output modules (fieldtwin.tsx.discrete).

Inputs are named by the hex digit of their object bit, as the program writes them
(``"B"`` is I2,B): a value is ``1``/``0``, ``on``/``off``, ``true``/``false``, or a
discrete signal table.  Output modules have no inputs.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from pathlib import Path

from fieldtwin.devices.common import apply_faults, apply_inputs
from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import (
    Family,
    Input,
    InputValue,
    ModuleAddress,
    Output,
    OutputValue,
    SignalSpec,
)
from fieldtwin.devices.kind import Build, DeviceKind
from fieldtwin.devices.module import IDENTITY, ModuleDevice, insert_module, own_keys
from fieldtwin.devices.schema import Key, Schema, Table
from fieldtwin.errors import ConfigError
from fieldtwin.signals import discrete_from_spec
from fieldtwin.tsx.dem24 import Dem24
from fieldtwin.tsx.discrete import MODULE_TYPES
from fieldtwin.tsx.discrete.module import DiscreteInputs, DiscreteOutputs
from fieldtwin.tsx.module import IntelligentModule
from fieldtwin.tsx.plc import Plc

LEVELS = {"1": True, "0": False, "on": True, "off": False, "true": True, "false": False}


class DiscreteDevice(ModuleDevice):
    def __init__(self, module: IntelligentModule, plc: Plc) -> None:
        super().__init__(module, plc)
        self.discrete = module

    def inputs(self) -> Mapping[str, Input]:
        module = self.discrete
        if not isinstance(module, DiscreteInputs):
            return {}
        return {
            f"{p:X}": Input(
                f"{p:X}", "contact: 1/0, on/off", partial(self._set, p), partial(self._drive, p)
            )
            for p in range(module.points)
        }

    def outputs(self) -> Mapping[str, Output]:
        """An output module's points ``"0"``..``"F"``, as the program wrote them (Oxy,i)."""
        module = self.discrete
        if not isinstance(module, DiscreteOutputs):
            return {}
        return {
            f"{p:X}": Output(f"{p:X}", "digital", partial(self._output, module, p))
            for p in range(module.discrete_outputs)
        }

    @staticmethod
    def _output(module: DiscreteOutputs, point: int) -> OutputValue:
        return OutputValue(f"{point:X}", bool(module.output(point)))

    def _set(self, point: int, value: InputValue) -> None:
        assert isinstance(self.discrete, DiscreteInputs)
        if isinstance(value, int | float) and not isinstance(value, bool) and value in (0, 1):
            value = bool(value)
        text = str(value).strip().lower()
        if isinstance(value, bool) or text in LEVELS:
            level = value if isinstance(value, bool) else LEVELS[text]
        else:
            raise ConfigError(f"input {point:X}: {value!r} not allowed (allowed: 1/0, on/off)")
        self.discrete.set_input(point, level)

    def _drive(self, point: int, spec: SignalSpec, where: str, base: Path | None) -> None:
        assert isinstance(self.discrete, DiscreteInputs)
        self.discrete.drive(point, discrete_from_spec(spec, where=where, base_dir=base))

    def configure(self, table: Table, ctx: BuildContext, where: str) -> None:
        inputs = table.get("inputs", {})
        if not isinstance(inputs, Mapping):
            raise ConfigError(f"{where}.inputs: a table of input = value or signal")
        apply_inputs(self, inputs, f"{where}.inputs", ctx.base_dir)
        apply_faults(self, table.get("faults", []), f"{where}.faults")
        wires = table.get("wires", {})
        if not isinstance(wires, Mapping):
            raise ConfigError(
                f'{where}.wires: a table like {{ "4" = {{ slot = 4, input = "sync" }} }}'
            )
        for point, target in wires.items():
            at = f"{where}.wires.{point}"
            ctx.after_build(partial(self._wire_at, str(point), target, ctx, at))

    def _wire_at(self, point: str, target: object, ctx: BuildContext, where: str) -> None:
        try:
            self._wire(point, target, ctx, where)
        except ConfigError as exc:
            text = str(exc)
            raise ConfigError(text if text.startswith(where) else f"{where}: {text}") from None

    def _wire(self, point: str, target: object, ctx: BuildContext, where: str) -> None:
        """An output wired to an input of another module of the plant (its Device face;
        ``input = "sync"`` is a DEM's IN-SYN, DEM 5.3-4 O3,4)."""
        module = self.discrete
        if not isinstance(module, DiscreteOutputs):
            raise ConfigError(f"{where}: {module.type_name} has no outputs to wire")
        try:
            index = int(point, 16)
        except ValueError:
            raise ConfigError(f"{where}: {point!r} is not an output (allowed 0..F)") from None
        if not isinstance(target, Mapping) or not {"slot", "input"} <= set(target):
            raise ConfigError(f'{where}: a table {{ rack = 0, slot = 4, input = "sync" }}')
        rack, slot, name = target.get("rack", 0), target["slot"], target["input"]
        if not isinstance(name, str) or any(
            isinstance(v, bool) or not isinstance(v, int) for v in (rack, slot)
        ):
            raise ConfigError(f'{where}: rack and slot are numbers, input a name ("sync")')
        found = [
            d
            for d in ctx.devices
            if isinstance(d, ModuleDevice) and d.address == ModuleAddress(rack, slot)
        ]
        if not found:
            raise ConfigError(f"{where}: no module in rack {rack} slot {slot}")
        other = found[0]
        if name == "sync" and isinstance(other.module, Dem24):
            module.wire(index, other.module.set_sync_input)
            return
        entry = other.input(name)

        def receive(level: bool) -> None:
            entry.set(int(level))

        module.wire(index, receive)


def _builder(cls: type[IntelligentModule]) -> Build:
    def build(table: Table, ctx: BuildContext, where: str) -> DiscreteDevice:
        module, plc = insert_module(table, ctx, where)
        assert isinstance(module, cls)
        device = DiscreteDevice(module, plc)
        device.configure(own_keys(table), ctx, where)
        return device

    return build


SCHEMA = Schema(
    IDENTITY,
    (
        Key("inputs", '{ "0" = 1 or a signal, ... "F" }'),
        Key("faults", "names"),
        Key("wires", '{ "4" = { rack, slot, input } } an output to another input'),
    ),
)
KINDS = tuple(
    DeviceKind(name, Family.MODULE, SCHEMA, _builder(cls), cls)
    for name, cls in MODULE_TYPES.items()
)
