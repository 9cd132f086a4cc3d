"""What the adapter of every TSX module kind shares: identity, status, faults, PL7 objects.

A module adapter wraps the module core the PLC built; everything kind-specific
(its inputs, its plant keys, its ports) is in that kind's own adapter file.
``ModuleDevice`` alone is the face of a module class that only the PLC's type
table knows: its faults are its kind's table (``devices.faults``) or the core's own
``fault_names`` / ``inject_fault`` (``NamedFaults``),
its inputs the core's typed ``set_input(channel, level)`` if it has one
(``PointInputs``), and it takes no plant key but ``faults``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from functools import partial
from typing import Protocol, runtime_checkable

from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import (
    DeviceStatus,
    Family,
    Fault,
    FaultParam,
    FrontPanel,
    Input,
    InputValue,
    ModuleAddress,
    ObjectEntry,
    Output,
    Port,
    PortState,
    Stream,
    active_faults,
    pick_fault,
    pick_input,
    read_outputs,
)
from fieldtwin.devices.faults import FaultTable, table_for
from fieldtwin.devices.schema import Key, Schema, Table, integer, optional_integer, string
from fieldtwin.errors import ConfigError
from fieldtwin.tsx.addressing import format_object, parse_object
from fieldtwin.tsx.bus import ModuleState
from fieldtwin.tsx.module import IntelligentModule
from fieldtwin.tsx.plc import Plc

POINT_INPUTS = 16  # the on/off inputs a module without a face of its own may offer


@runtime_checkable
class PointInputs(Protocol):
    """A module core only the PLC knows, with typed on/off inputs ``0``..``15``."""

    def set_input(self, channel: int, level: bool) -> None: ...


IDENTITY = (
    Key("type", 'the module type, e.g. "TSX AEM 811"'),
    Key("rack", "rack number (default 0)"),
    Key("slot", "slot number"),
    Key("code", "the code the slot is declared with (optional)"),
)


class PlcObjects:
    """A module's PL7 objects as the PLC program sees them (no side effects)."""

    def __init__(self, plc: Plc, address: ModuleAddress) -> None:
        self._plc = plc
        self._address = address

    def names(self) -> list[ObjectEntry]:
        a = self._address
        words = [ObjectEntry(f"{kind}{a},{i}") for kind in ("IW", "OW") for i in range(8)]
        return [*words, ObjectEntry(f"I{a},S")]

    def read(self, name: str) -> int:
        self._own(name)
        return self._plc.read(name)

    def peek(self, name: str) -> int:
        return self.read(name)  # a PL7 object read by the program has no side effect

    def write(self, name: str, value: int) -> None:
        self._own(name)
        self._plc.write(name, value)

    def _own(self, name: str) -> None:
        ref = parse_object(name)
        if (ref.rack, ref.slot) != (self._address.rack, self._address.slot):
            raise ConfigError(
                f"{format_object(ref)} is not an object of the module in slot {self._address}"
            )


class ModuleDevice:
    """The Device face of one module in one PLC slot."""

    def __init__(self, module: IntelligentModule, plc: Plc) -> None:
        self.module = module
        self.plc = plc
        # the faults set through this face and not cleared since, with their parameters
        # (a module's fault is a condition put on it: a cut wire stays cut until cleared)
        self.in_force: dict[str, dict[str, FaultParam]] = {}

    # --- identity ---------------------------------------------------------

    @property
    def kind(self) -> str:
        return self.module.type_name

    @property
    def family(self) -> Family:
        return Family.MODULE

    @property
    def address(self) -> ModuleAddress:
        return ModuleAddress(self.module.rack, self.module.slot)

    # --- the face -----------------------------------------------------------

    def status(self) -> DeviceStatus:
        m = self.module
        return DeviceStatus(
            kind=self.kind,
            address=str(self.address),
            state=m.state.value,
            mode=self.mode(),
            leds=self.leds(),
            ports=tuple(self.port_states()),
            details=tuple({**m.status(), **self.details()}.items()),
            active_faults=active_faults(self.faults()),
            outputs=read_outputs(self.outputs()),
        )

    def mode(self) -> str | None:
        """Run / Stop where the module has them; None where it has none."""
        m = self.module
        if not m.has_run_stop:
            return None
        if m.state is not ModuleState.OPERATIONAL:
            return None
        return "Run" if m.running else "Stop"

    def details(self) -> dict[str, str]:
        """The kind's own status lines, after the module's (none for a generic module)."""
        return {}

    def leds(self) -> tuple[tuple[str, str], ...]:
        """The module's front-panel LEDs: (name, "on" | "off" | "blink")."""
        return tuple(self.module.leds.items())

    def port_states(self) -> list[PortState]:
        return []

    def inputs(self) -> Mapping[str, Input]:
        """None, unless the core has typed on/off inputs of its own (``PointInputs``)."""
        m = self.module
        if not isinstance(m, PointInputs):
            return {}
        return {
            str(ch): Input(str(ch), "0 or 1", partial(self._point, m, ch))
            for ch in range(POINT_INPUTS)
        }

    def _point(self, m: PointInputs, channel: int, value: InputValue) -> None:
        text = value if isinstance(value, str) else str(int(value))
        if text not in ("0", "1"):
            raise ConfigError(f"input value {text!r} not allowed (allowed 0 or 1)")
        m.set_input(channel, text == "1")

    def input(self, name: str) -> Input:
        return pick_input(self, name.strip())

    def faults(self) -> Mapping[str, Fault]:
        m = self.module
        table = table_for(m)
        return {
            name: self.tracked(name, text, partial(self._inject, table, name))
            for name, text in table.names(m).items()
        }

    def _inject(self, table: FaultTable, name: str, active: bool) -> None:
        table.inject(self.module, name, active, {})

    def tracked(self, name: str, description: str, setter: Callable[[bool], None]) -> Fault:
        """A fault without parameters whose state is what this face last set."""
        return Fault(
            name,
            description,
            partial(self._set_tracked, name, setter),
            state=partial(self.in_force.get, name),
        )

    def _set_tracked(self, name: str, setter: Callable[[bool], None], active: bool) -> None:
        setter(active)
        if active:
            self.in_force[name] = {}
        else:
            self.in_force.pop(name, None)

    def outputs(self) -> Mapping[str, Output]:
        """None for a module without a face of its own."""
        return {}

    def streams(self) -> Sequence[Stream]:
        return ()

    def fault(self, name: str) -> Fault:
        return pick_fault(self, name)

    def objects(self) -> PlcObjects:
        return PlcObjects(self.plc, self.address)

    def ports(self) -> list[Port]:
        return []

    def panel(self) -> FrontPanel:
        """The LEDs and the core's status lines (a kind's adapter shows more)."""
        return FrontPanel(
            self.leds(), fields=tuple({**self.module.status(), **self.details()}.items())
        )

    # --- plant file -----------------------------------------------------------

    def configure(self, table: Table, ctx: BuildContext, where: str) -> None:
        """The kind's own keys (identity keys are gone): a module without a face of its
        own takes ``faults`` (names set at start) and nothing else."""
        rest = dict(table)
        names = rest.pop("faults", [])
        if not isinstance(names, list):
            raise ConfigError(f"{where}.faults: {names!r} is not a list of fault names")
        for name in names:
            try:
                self.fault(str(name)).set(True)
            except ConfigError as exc:
                raise ConfigError(f"{where}: {exc}") from None
        if rest:
            raise ConfigError(f"{where}: unknown keys {sorted(rest)} for {self.kind}")

    def bind(self, port: Port, runner: object) -> list[str]:
        raise ConfigError(f"{self.kind} in slot {self.address} has no port {port.name!r}")


def insert_module(table: Table, ctx: BuildContext, where: str) -> tuple[IntelligentModule, Plc]:
    """Put the module a ``[[module]]`` table names into its slot (field-path errors)."""
    plc = ctx.require_plc(where)
    type_name = string(table, "type", where, '"TSX AEM 811"')
    rack = integer(table, "rack", where, 0)
    slot = integer(table, "slot", where)
    code = optional_integer(table, "code", where)
    try:
        module: IntelligentModule = plc.insert(type_name, rack=rack, slot=slot, code=code)
    except ConfigError as exc:
        text = str(exc)
        field_name = "type" if "module type" in text else "rack" if "rack" in text else "slot"
        raise ConfigError(f"{where}.{field_name}: {exc}") from None
    return module, plc


def own_keys(table: Table) -> dict[str, object]:
    """The table without the identity keys the plant builder read."""
    identity = {key.name for key in IDENTITY}
    return {k: v for k, v in table.items() if k not in identity}


def build_generic(table: Table, ctx: BuildContext, where: str) -> ModuleDevice:
    """A module class only the PLC's type table knows: its core reads its own keys."""
    module, plc = insert_module(table, ctx, where)
    device = ModuleDevice(module, plc)
    try:
        device.configure(own_keys(table), ctx, where)
    except ConfigError as exc:
        message = str(exc)
        raise ConfigError(message if message.startswith(where) else f"{where}: {message}") from None
    return device


GENERIC_SCHEMA = Schema(IDENTITY, open=True)
