"""The Device face of the Leroy TES remote I/O terminals (docs/tes.md).

Address: the endpoint and the slave number on it.  Inputs: ``"0"``..``"31"``
digital (true/false, 1/0, on/off; a discrete signal), ``"a0"``..``"a7"``
analog (volts or milliamps; an analog signal); on a TES with analog inputs
only, ``"2"`` is ``"a2"`` (the console's older form).  Faults: the TES core's
catalogue (``fieldtwin.devices.tes.faults``): ``power_off`` (24 V off), the line faults
``no_answer``, ``late_answer`` (ms), ``bad_crc``, ``broken_character``,
``not_ready``, and on the TES 32ET-S ``short_I`` / ``open_I`` (wiring, §4.1.5).
Objects: the words of the memory map by address or name, read as a master
reads them (with side effects: memorized inputs restored) or peeked.
Every TES-specific call of the face is in this file.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from functools import partial
from pathlib import Path

from fieldtwin.charformat import CharFormat, line_settings
from fieldtwin.devices.common import apply_faults, apply_inputs
from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import (
    SHARED_MODBUS,
    BitRow,
    DeviceStatus,
    Family,
    Fault,
    FaultParam,
    FrontPanel,
    Input,
    InputValue,
    ModbusSlave,
    ObjectEntry,
    Output,
    OutputValue,
    PanelWord,
    Port,
    PortKind,
    PortState,
    Reading,
    SignalSpec,
    Stream,
    TesAddress,
    active_faults,
    applicable,
    pick_fault,
    read_outputs,
)
from fieldtwin.devices.kind import Build, DeviceKind
from fieldtwin.devices.schema import Key, Schema, Table
from fieldtwin.devices.tes.faults import FAULTS, fault_catalogue
from fieldtwin.devices.tes.plantkeys import KEYS, build_one, check_lines, link_of
from fieldtwin.devices.tes.values import analog_value, contact_value
from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import Link
from fieldtwin.signals import analog_from_spec, discrete_from_spec
from fieldtwin.tes.memmap import register_names, register_table
from fieldtwin.tes.model import Tes
from fieldtwin.tes.models import MODELS, TesModel
from fieldtwin.tes.state import link_key
from fieldtwin.words import format_hex, parse_word

GROUP = SHARED_MODBUS  # TES on one endpoint share one line

# The kinds of port a TES is reached through (by the endpoint's scheme) and the line
# faults that mean something there: a CRC or a broken character exists only where RTU
# frames travel; a connection to drop only where TCP carries them.
RTU_FAULTS = ("bad_crc", "broken_character")
TCP_FAULTS = ("drop_connections",)
MODBUS_TCP = PortKind("Modbus TCP", TCP_FAULTS)
RTU_OVER_TCP = PortKind("RTU over TCP", RTU_FAULTS + TCP_FAULTS)
RTU_LINE = PortKind("RTU line", RTU_FAULTS)
IN_MEMORY = PortKind("in-memory line", RTU_FAULTS)  # an RtuLine in the same process (tests)
PORT_KINDS = {
    "tcp": MODBUS_TCP,
    "rtu+tcp": RTU_OVER_TCP,
    "pty": RTU_LINE,
    "serial": RTU_LINE,
    "memory": IN_MEMORY,
}
LINE_FAULTS = RTU_FAULTS + TCP_FAULTS


def port_kind(endpoint: str) -> PortKind:
    """The kind of port an endpoint URL is (``tcp://...``: Modbus TCP)."""
    scheme = endpoint.split("://", 1)[0] if "://" in endpoint else endpoint.split("?", 1)[0]
    return PORT_KINDS.get(scheme.strip().lower(), RTU_LINE)


def kinds_carrying(fault: str) -> tuple[str, ...]:
    """The port kinds a line fault applies to; () for a fault of the TES itself."""
    if fault not in LINE_FAULTS:
        return ()
    kinds = (MODBUS_TCP, RTU_OVER_TCP, RTU_LINE)
    return tuple(k.name for k in kinds if fault in k.line_faults)


class TesRegisters:
    """The TES words by address (``H'003'``, ``0x003``, ``3``) or by their map name."""

    def __init__(self, tes: Tes) -> None:
        self._tes = tes

    def names(self) -> list[ObjectEntry]:
        return list(_entries(self._tes.model))

    def address(self, name: str) -> int:
        token = name.strip()
        if token[:2].upper() == "H'" or token[:1].isdigit():  # an address: no name search
            try:
                return int(token, 0) if token.lower().startswith("0x") else parse_word(token)
            except ConfigError:
                pass
        for reg in register_names(self._tes.model).values():
            if reg.name.lower() == token.lower():
                return reg.address
        try:
            return int(token, 0) if token.lower().startswith("0x") else parse_word(token)
        except ConfigError:
            raise ConfigError(f"{self._tes.model.name}: no word {name!r}") from None

    def read(self, name: str) -> int:
        return self._tes.read(self.address(name))

    def peek(self, name: str) -> int:
        return self._tes.peek(self.address(name))

    def peeker(self, name: str) -> Callable[[], int]:
        """A peek at ``name`` with its word number found once (face.peeker)."""
        address = self.address(name)
        tes = self._tes
        return lambda: tes.peek(address)

    def write(self, name: str, value: int) -> None:
        self._tes.write(self.address(name), value)


def tes_line_format(tes: Tes, link: Link) -> CharFormat:
    """§3.1.3: speed and parity are parameters; 8 data bits and 1 stop bit are fixed."""
    key = link_key(link)
    baud, parity = tes.params[f"{key}.baud"], tes.params[f"{key}.parity"]
    assert isinstance(baud, int) and isinstance(parity, str)
    return line_settings(baud=baud, data_bits=8, parity=parity, stop_bits=1)


def modbus_slave(
    tes: Tes, link: Link, drop: Callable[[Callable[[], int] | None], None] | None = None
) -> ModbusSlave:
    """What the runtime serves of ``tes`` on the port ``link`` names (docs/tes.md)."""
    key = link_key(link)
    return ModbusSlave(
        tes,
        link,
        tes.name,
        tes_line_format(tes, link),
        f"{key}.baud / {key}.parity; change them with `fieldtwin tesis`",
        "the TES",
        tes.wire_timing,
        drop,
        strict_line=tes.strict_line,
    )


class TesDevice:
    """A TES on its endpoint, with the table it came from (for the line checks)."""

    def __init__(self, tes: Tes, endpoint: str, link: Link, table: Table, where: str) -> None:
        self.tes = tes
        self.endpoint = endpoint
        self.link = link
        self.table = table
        self.where = where
        self._dropping: list[Callable[[], int]] = []  # what this face gave the TES to drop

    @property
    def kind(self) -> str:
        return self.tes.model.name

    @property
    def family(self) -> Family:
        return Family.TES

    @property
    def address(self) -> TesAddress:
        return TesAddress(self.endpoint, self.tes.slave)

    def status(self) -> DeviceStatus:
        tes = self.tes
        details = (("status", format_hex(tes.status_word())),) if tes.powered else ()
        return DeviceStatus(
            kind=self.kind,
            address=str(self.address),
            state="on" if tes.powered else "off",
            mode=None,
            leds=tuple(tes.leds.items()),
            ports=(PortState(self.link.value, self.endpoint),),
            details=details,
            active_faults=active_faults(self.faults()),
            outputs=read_outputs(self.outputs()),
        )

    # --- inputs ---------------------------------------------------------------

    def inputs(self) -> Mapping[str, Input]:
        model = self.tes.model
        found = {str(i): self._digital(i) for i in range(model.digital_inputs)}
        found.update({f"a{k}": self._analog(k) for k in model.analog_inputs})
        return found

    def input(self, name: str) -> Input:
        text = name.strip().lower()
        model = self.tes.model
        analog = text.startswith("a")
        number = text[1:] if analog else text
        if not number.isdigit():
            raise ConfigError(f"not an input (allowed 0..31 digital, a0..a7 analog) of {self.kind}")
        i = int(number)
        if not analog and not model.digital_inputs and model.analog_inputs:
            analog = True  # `tes 2 input 0 5.0` on an analog TES
        if analog:
            if i not in model.analog_inputs:
                allowed = ", ".join(map(str, model.analog_inputs)) or "none"
                raise ConfigError(f"{self.kind}: no analog input {i} (allowed: {allowed})")
            return self._analog(i)
        if not 0 <= i < model.digital_inputs:
            top = f"0..{model.digital_inputs - 1}" if model.digital_inputs else "none"
            raise ConfigError(f"{self.kind}: no digital input {i} (allowed {top})")
        return self._digital(i)

    def _digital(self, i: int) -> Input:
        return Input(
            str(i),
            "digital: 1/0, on/off, true/false",
            lambda v: self._contact(i, v),
            lambda s, w, b: self._drive(i, s, w, b, True),
        )

    def _analog(self, k: int) -> Input:
        unit = self.tes.model.analog_range.unit
        return Input(
            f"a{k}",
            f"analog, {unit}",
            lambda v: self._level(k, v),
            lambda s, w, b: self._drive(k, s, w, b, False),
        )

    def _contact(self, i: int, value: InputValue) -> None:
        self.tes.set_input(i, contact_value(self.kind, i, value))

    def _level(self, k: int, value: InputValue) -> str | None:
        level = analog_value(self.kind, k, value)
        return self.tes.set_input(k, level)  # the note of a level beyond the span (§4.2.4)

    def _drive(
        self, i: int, spec: SignalSpec, where: str, base: Path | None, digital: bool
    ) -> None:
        if digital:
            self.tes.set_signal(i, discrete_from_spec(spec, where=where, base_dir=base), True)
        else:
            self.tes.set_signal(i, analog_from_spec(spec, where=where, base_dir=base), False)

    # --- faults -----------------------------------------------------------------

    def faults(self) -> Mapping[str, Fault]:
        """The faults that apply to this TES on its port (docs/tes.md, "Faults")."""
        return applicable(self.every_fault(), self.ports())

    def every_fault(self) -> dict[str, Fault]:
        """The TES core's fault catalogue for this model, whatever its port."""
        tes = self.tes
        return {
            spec.name: Fault(
                spec.name,
                spec.description,
                partial(self._inject, spec.name),
                spec.params,
                partial(self._inject_with, spec.name) if spec.params else None,
                state=partial(self._in_force, spec.name),
                port_kinds=kinds_carrying(spec.name),
            )
            for spec in fault_catalogue(tes.model).values()
        }

    def fault(self, name: str) -> Fault:
        return pick_fault(self, name, self.every_fault())

    def _in_force(self, name: str) -> Mapping[str, FaultParam] | None:
        return self.tes.active_faults().get(name)

    def _inject(self, name: str, on: bool) -> None:
        FAULTS.inject(self.tes, name, on, {})

    def _inject_with(self, name: str, on: bool, params: Mapping[str, FaultParam]) -> None:
        FAULTS.inject(self.tes, name, on, params)

    # --- outputs ----------------------------------------------------------------

    def outputs(self) -> Mapping[str, Output]:
        """Digital outputs ``0``..; analog outputs ``a4``.. in volts or milliamps (§4.3.1),
        with the word the master wrote beside."""
        model = self.tes.model
        found = {
            str(i): Output(str(i), "digital", partial(self._digital_out, i))
            for i in range(model.digital_outputs)
        }
        unit = model.analog_range.unit
        found.update(
            {
                f"a{k}": Output(f"a{k}", f"analog, {unit}", partial(self._analog_out, k))
                for k in model.analog_outputs
            }
        )
        return found

    def _digital_out(self, i: int) -> OutputValue:
        return OutputValue(str(i), self.tes.digital_output(i))

    def _analog_out(self, k: int) -> OutputValue:
        tes = self.tes
        unit = tes.model.analog_range.unit
        volts = round(tes.analog_output(k), 4) if tes.powered else 0.0
        return OutputValue(f"a{k}", volts, unit, tes.analog_output_word(k))

    def streams(self) -> Sequence[Stream]:
        return ()  # its register writes are published by the endpoint's wiretap

    def objects(self) -> TesRegisters:
        return TesRegisters(self.tes)

    def ports(self) -> list[Port]:
        tes, link = self.tes, self.link
        slave = modbus_slave(tes, link, self._droppers)
        return [Port(link.value, self.endpoint, GROUP, port_kind(self.endpoint), slave)]

    def _droppers(self, drop: Callable[[], int] | None) -> None:
        """The endpoint's connection dropper while it serves this TES (drop_connections)."""
        droppers = self.tes.line_faults.droppers
        if drop is not None:
            droppers.append(drop)
            self._dropping.append(drop)
            return
        for old in self._dropping:
            if old in droppers:
                droppers.remove(old)
        self._dropping.clear()

    def panel(self) -> FrontPanel:
        """Its LEDs, inputs and outputs, edge counters, analog inputs in volts or
        milliamps with the converter's points (§4.2.4), and the watchdog word (tenths of
        a second, §6.3), all peeked: a memorized input stays memorized."""
        tes = self.tes
        leds = tuple(tes.leds.items())
        if not tes.powered:
            return FrontPanel(leds, fields=(("status", ""),))
        model = tes.model
        names = {reg.name: reg.address for reg in register_names(model).values()}

        def peek(name: str) -> int:
            return tes.peek(names[name]) if name in names else 0

        if "direct_io" in names:  # an analog model: bits 0..3 inputs, 8..B outputs (§6.4)
            direct = peek("direct_io") & 0xF
        else:
            direct = peek("direct[0]") | (peek("direct[1]") << 16)
        bits = (
            BitRow("in", tuple(bool(direct >> i & 1) for i in range(model.digital_inputs))),
            BitRow("out", tuple(tes.digital_output(i) for i in range(model.digital_outputs))),
        )
        counters = []
        for i in range(model.digital_inputs):
            rise, fall = f"counter_rise[{i}]", f"counter_fall[{i}]"
            if f"{rise}.high" in names:
                rises = (peek(f"{rise}.high") << 16) | peek(f"{rise}.low")
                falls = (peek(f"{fall}.high") << 16) | peek(f"{fall}.low")
                counters.append(Reading(str(i), rises, "rises", more=(("fall", falls),)))
        unit = model.analog_range.unit
        analog = []
        for k in model.analog_inputs:
            word = peek(f"analog_input[{k}]")
            points = word - 0x10000 if word & 0x8000 else word
            more = (("points", points), ("full_scale", model.analog_range.full_scale))
            level = round(tes.ai.level(k, tes.clock.now), 4)
            analog.append(Reading(f"a{k}", level, unit, more=more))
        watchdog = peek("watchdog")
        return FrontPanel(
            leds,
            bits=bits,
            words=(PanelWord("watchdog", watchdog),),
            readings=tuple(analog),
            frozen=tuple(counters),
            fields=(("status", format_hex(tes.status_word())), ("watchdog_s", watchdog / 10)),
        )

    def label(self) -> str:
        """``TES 1 TES 32EST``: the slave number, then the model (endpoint in status lines)."""
        return f"TES {self.tes.slave} {self.kind}"


@functools.cache
def _entries(model: TesModel) -> tuple[ObjectEntry, ...]:
    """The words of a model's memory map, once per model (the dashboard asks each poll)."""
    table = register_table(model)
    return tuple(ObjectEntry(format_hex(a, 3), r.name) for a, r in sorted(table.items()))


SCHEMA = Schema(
    (
        Key("model", 'the TES model, e.g. "TES 32EST"'),
        Key("slave", "the slave number on the port `link` names, 1..247"),
        Key("endpoint", "tcp://HOST:PORT, rtu+tcp://HOST:PORT, pty, serial:///DEVICE"),
        Key("link", "the TES port the endpoint is: rs485 or rs232"),
    ),
    tuple(
        Key(k, "see docs/tes.md") for k in KEYS if k not in ("model", "slave", "endpoint", "link")
    ),
)


def _builder() -> Build:
    def build(table: Table, ctx: BuildContext, where: str) -> TesDevice:
        tes = build_one(table, ctx.clock, where, ctx.base_dir, signals=False)
        device = TesDevice(tes, str(table["endpoint"]), link_of(table, where), table, where)
        inputs = table.get("inputs", {})
        if not isinstance(inputs, Mapping):
            raise ConfigError(f"{where}.inputs: not a table (e.g. {{ 0 = true, a2 = 4.5 }})")
        ctx.notes += apply_inputs(device, inputs, f"{where}.inputs", ctx.base_dir)
        faults = table.get("faults")
        if isinstance(faults, list):
            apply_faults(device, faults, f"{where}.faults")
        if not any(isinstance(d, TesDevice) for d in ctx.devices):
            ctx.after_build(lambda: _check(ctx))
        return device

    return build


def _check(ctx: BuildContext) -> None:
    devices = [d for d in ctx.devices if isinstance(d, TesDevice)]
    check_lines([d.tes for d in devices], [d.table for d in devices], ctx.name)


KINDS = tuple(DeviceKind(name, Family.TES, SCHEMA, _builder()) for name in MODELS)
