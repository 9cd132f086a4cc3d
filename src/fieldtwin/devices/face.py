"""The one face every twin shows: the Device protocol and the values it returns.

Everything above ``fieldtwin.devices`` (the plant file, the console, the live
view, the runtime's binder) speaks to a device only through :class:`Device`;
a device kind's adapter (one file in this package) maps its core onto it.

Naming scheme (docs/architecture.md, "Inputs and faults"): an input is named by
its channel number (``"0"``), a TES analog input by ``a`` + its number
(``"a2"``), a named line of a channel by channel + ``.`` + the line's name
(``"0.CTS"``); a fault by the name its device lists (``"terminal_block"``,
``"open_3"``).  The same names serve the plant file, the console and Python.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Protocol

from fieldtwin.charformat import CharFormat
from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import Link, SlaveDevice
from fieldtwin.words import format_hex

InputValue = bool | float | str  # a contact, a value in the input's unit, or console text
SignalSpec = Mapping[str, object]  # a plant-file signal table: { kind = "sine", ... }
LedState = str  # "on", "off" or "blink"


@dataclass(frozen=True, slots=True)
class Family:
    """A family of devices: how a plant file lists them and how users name a kind.

    An open set: ``Family.MODULE`` and ``Family.TES`` are fieldtwin's; a third family
    is one more value made in its own package (``Family("pump", "pump", "model",
    "pump model")``) and registered with its kinds.  ``value`` is the name the API
    shows (``"module"``, ``"tes"``); ``table`` the plant file's ``[[table]]``; ``key``
    the key naming the kind in it (``type``, ``model``); ``what`` the kind in errors."""

    value: str
    table: str
    key: str
    what: str
    title: str = ""  # how the live view heads the family's table ("TES remote I/O")

    MODULE: ClassVar[Family]  # a TSX intelligent module in a rack slot
    TES: ClassVar[Family]  # a Leroy TES remote I/O terminal on a Modbus endpoint

    def __str__(self) -> str:
        return self.value


Family.MODULE = Family("module", "module", "type", "module type")
Family.TES = Family("tes", "tes", "model", "TES model", "TES remote I/O")


class Address(Protocol):
    """Where a device is, as every window names it; each family's address implements it.

    ``text`` is how the console writes it (``5``, ``23``, ``tcp://127.0.0.1:5020 1``);
    ``key`` orders and identifies it; ``selects(token)`` says whether a user's token
    names it; ``ident(peers)`` is its id in the control API among the addresses of
    every device of the plant (``5``, ``tes1``, ``tes1@2``).  ``label`` names the
    device in a one-line status (``slot 5``, ``TES 1``), ``where`` says where it is
    reached (``rack 0``, ``tcp://127.0.0.1:5020``), ``columns`` gives the address as
    a table's columns (``(("endpoint", ...), ("slave", "1"))``)."""

    @property
    def text(self) -> str: ...

    @property
    def label(self) -> str: ...

    @property
    def where(self) -> str: ...

    @property
    def columns(self) -> tuple[tuple[str, str], ...]: ...

    @property
    def key(self) -> tuple[object, ...]: ...

    def selects(self, token: str) -> bool: ...

    def ident(self, peers: Sequence[Address]) -> str: ...


@dataclass(frozen=True, slots=True)
class ModuleAddress:
    """Rack and slot; written as the console writes it: ``5`` (rack 0) or ``23``."""

    rack: int
    slot: int

    def __str__(self) -> str:
        return f"{self.slot}" if self.rack == 0 else f"{self.rack}{self.slot}"

    @property
    def text(self) -> str:
        return str(self)

    @property
    def key(self) -> tuple[object, ...]:
        return ("module", self.rack, self.slot)

    @property
    def label(self) -> str:
        return f"slot {self}"

    @property
    def where(self) -> str:
        return f"rack {self.rack}"

    @property
    def columns(self) -> tuple[tuple[str, str], ...]:
        return (("slot", str(self)),)

    def selects(self, token: str) -> bool:
        return token.strip() == str(self)

    def ident(self, peers: Sequence[Address]) -> str:
        return str(self)


@dataclass(frozen=True, slots=True)
class TesAddress:
    """An endpoint and a slave number on it, as the console names it:
    ``tcp://127.0.0.1:5020 1`` (``tes tcp://127.0.0.1:5020 1 read H'000'``)."""

    endpoint: str
    slave: int

    def __str__(self) -> str:
        return f"{self.endpoint} {self.slave}"

    @property
    def text(self) -> str:
        return str(self)

    @property
    def key(self) -> tuple[object, ...]:
        return ("tes", self.endpoint, self.slave)

    @property
    def label(self) -> str:
        return f"TES {self.slave}"

    @property
    def where(self) -> str:
        return self.endpoint

    @property
    def columns(self) -> tuple[tuple[str, str], ...]:
        return (("endpoint", self.endpoint), ("slave", str(self.slave)))

    def selects(self, token: str) -> bool:
        return " ".join(token.split()) == str(self)

    def ident(self, peers: Sequence[Address]) -> str:
        """``tes1``; ``tes1@2`` when slave 1 answers on several endpoints (the second
        endpoint in file order)."""
        endpoints: list[str] = []
        for other in peers:
            if (
                isinstance(other, TesAddress)
                and other.slave == self.slave
                and other.endpoint not in endpoints
            ):
                endpoints.append(other.endpoint)
        index = endpoints.index(self.endpoint)
        return f"tes{self.slave}" if index == 0 else f"tes{self.slave}@{index + 1}"


@dataclass(frozen=True, slots=True)
class PortKind:
    """What a port is (``Modbus TCP``, ``RTU line``, ``SCM channel``...) and the line
    faults that mean something on it (``bad_crc`` on an RTU line, not on Modbus TCP)."""

    name: str
    line_faults: tuple[str, ...] = ()


ANY_PORT = PortKind("port")  # a port that declares no kind of its own: no line fault applies


@dataclass(frozen=True, slots=True)
class PortState:
    """One port of a device and the state of its line, for people."""

    name: str  # "channel 0", "rs485"
    line: str  # "not wired", "pty /dev/pts/4", "tcp://127.0.0.1:5020"


@dataclass(frozen=True, slots=True)
class DeviceStatus:
    """A device as its front panel and its ports show it, at one instant."""

    kind: str
    address: str
    state: str
    mode: str | None  # Run / Stop where the device has such a mode, else None
    leds: tuple[tuple[str, LedState], ...]  # front-panel order
    ports: tuple[PortState, ...] = ()
    details: tuple[tuple[str, str], ...] = ()  # device-specific lines (console status)
    active_faults: tuple[ActiveFault, ...] = ()  # the faults in force, in the device's order
    outputs: tuple[OutputValue, ...] = ()  # every output the device drives, now

    @property
    def led_map(self) -> dict[str, LedState]:
        return dict(self.leds)

    def leds_text(self) -> str:
        return " ".join(f"{name}={state}" for name, state in self.leds)


@dataclass(frozen=True, slots=True)
class Input:
    """A named input: settable with a value, drivable by a signal spec."""

    name: str
    description: str  # its kind and unit: "analog, volts or milliamps"
    setter: Callable[[InputValue], str | None]  # returns a note (a level that saturates)
    driver: Callable[[SignalSpec, str, Path | None], None] | None = None

    def set(self, value: InputValue) -> str | None:
        """Set the input; a note when the device took it otherwise (e.g. saturated)."""
        return self.setter(value)

    def drive(self, spec: SignalSpec, *, where: str, base_dir: Path | None = None) -> None:
        if self.driver is None:
            raise ConfigError(
                f"{where}: input {self.name!r} takes no input signals, a value only"
                " (see the device's page for 'input')"
            )
        self.driver(spec, where, base_dir)


FaultParam = int | float
PARAM_EXAMPLES: dict[str, FaultParam] = {"ms": 200, "count": 3, "window_ms": 20}


@dataclass(frozen=True, slots=True)
class ActiveFault:
    """A fault in force and the parameters it is in force with (``{"ms": 200}``)."""

    name: str
    params: Mapping[str, FaultParam]

    def text(self) -> str:
        """``late_answer ms=200``, ``power_off``: as the console and the live view show it."""
        return " ".join([self.name, *(f"{k}={v:g}" for k, v in self.params.items())])


@dataclass(frozen=True, slots=True)
class OutputValue:
    """One output as it stands: its value in the device's units, the raw word beside.

    A bit is a bool with unit ``""``; an analog output a float in ``"V"`` or ``"mA"``
    with ``raw`` the word the master wrote; ``raw`` is None where there is no word."""

    name: str
    value: bool | float
    unit: str = ""
    raw: int | None = None

    def text(self) -> str:
        """``1``, ``0``, ``4.500V``, ``12.000mA (H'3FFF')``: as the console shows it."""
        if isinstance(self.value, bool):
            return str(int(self.value))
        word = "" if self.raw is None else f" (H'{self.raw & 0xFFFF:04X}')"
        return f"{self.value:.3f}{self.unit}{word}"


@dataclass(frozen=True, slots=True)
class Output:
    """A named output the device drives, named as the plant file names inputs."""

    name: str
    description: str  # "digital", "analog, volts"
    reader: Callable[[], OutputValue]

    def read(self) -> OutputValue:
        return self.reader()


@dataclass(frozen=True, slots=True)
class Fault:
    """A named fault: described, set (with its parameters, if it takes any) and cleared.

    ``params`` names what ``set`` takes (a TES's ``late_answer`` takes ``ms``);
    ``configure`` receives them.  A fault without parameters has only ``setter``.
    ``state`` tells whether it is in force: the parameters it is in force with, or
    None when it is not; a fault without ``state`` cannot tell (never shown active).
    ``port_kinds`` names the kinds of port a line fault means something on
    (``bad_crc``: an RTU line); empty, the fault is the device's own and always applies.
    """

    name: str
    description: str
    setter: Callable[[bool], None]
    params: tuple[str, ...] = ()
    configure: Callable[[bool, Mapping[str, FaultParam]], None] | None = None
    state: Callable[[], Mapping[str, FaultParam] | None] | None = None
    port_kinds: tuple[str, ...] = ()

    def in_force(self) -> Mapping[str, FaultParam] | None:
        """The parameters it is in force with (``{}`` for none), or None when it is not."""
        return None if self.state is None else self.state()

    @property
    def active(self) -> bool:
        return self.in_force() is not None

    def hint(self) -> str:
        """What ``set`` takes, as a user writes it: ``ms=200``, ``count=3``, ``""``."""
        return " ".join(f"{p}={PARAM_EXAMPLES.get(p, 1)}" for p in self.params)

    def set(self, active: bool = True, **params: FaultParam) -> None:
        if self.configure is not None:
            self.configure(active, params)
            return
        if params:
            raise ConfigError(
                f"fault {self.name!r} takes no parameters, not {', '.join(sorted(params))}"
            )
        self.setter(active)

    def clear(self) -> None:
        self.setter(False)


Publish = Callable[[int, Mapping[str, object]], None]  # (simulated time in µs, the event's data)


@dataclass(frozen=True, slots=True)
class Stream:
    """What a device emits, as it emits it (a DEM's messages with their stamps...).

    ``kind`` is the event kind the runtime publishes it under (``"dem"``);
    ``subscribe(publish)`` starts calling ``publish(now_us, data)`` on every
    item and returns the function that stops it.  One subscriber at a time."""

    kind: str
    description: str
    subscribe: Callable[[Publish], Callable[[], None]]


@dataclass(frozen=True, slots=True)
class ObjectEntry:
    """One object a master reads or writes: where it is and, if it has one, its name.

    ``address`` is what ``read`` / ``peek`` / ``write`` take (``IW5,3``, ``H'005'``);
    ``name`` the device's name for it (a TES's ``analog_input[0]``; ``""`` for a PL7
    object, whose address is its name)."""

    address: str
    name: str = ""

    @property
    def text(self) -> str:
        """``H'005' analog_input[0]``, ``IW5,3``: as the API and the console list it."""
        return f"{self.address} {self.name}" if self.name else self.address


class Objects(Protocol):
    """What a master reads and writes: PL7 objects of a module, registers of a TES."""

    def names(self) -> list[ObjectEntry]:
        """Every object, in the device's order."""
        ...

    def read(self, name: str) -> int:
        """A master's read, with its side effects (a TES's memorized inputs...)."""
        ...

    def peek(self, name: str) -> int:
        """The value as it stands, without side effects."""
        ...

    def write(self, name: str, value: int) -> None: ...


def peeker(objects: Objects, name: str) -> Callable[[], int]:
    """A peek at ``name`` bound once: a window that looks at the same object again and
    again (the recorder) asks for it without parsing the name each time.  An
    ``Objects`` may offer ``peeker(name)`` of its own (a TES binds the word's number);
    any other gets ``lambda: objects.peek(name)``."""
    own: Callable[[str], Callable[[], int]] | None = getattr(objects, "peeker", None)
    if own is not None:
        return own(name)
    return lambda: objects.peek(name)


@dataclass(frozen=True, slots=True)
class Port:
    """What the runtime may bind: an endpoint URL and the function that opens it."""

    name: str
    endpoint: str
    group: str  # ports with the same group and endpoint share one line ("modbus", "scm")
    kind: PortKind = ANY_PORT  # what the port is, and the line faults that apply to it
    # how the runtime opens it, by its group: a slave it serves on a shared Modbus
    # endpoint (SHARED_MODBUS), or the port's own opener (OWN_LINE); see "Ports by kind"
    modbus: ModbusSlave | None = None
    opener: Callable[[], Opened] | None = None


class Device(Protocol):
    """Every twin's face (docs/architecture.md)."""

    @property
    def kind(self) -> str: ...

    @property
    def family(self) -> Family: ...

    @property
    def address(self) -> Address: ...

    def status(self) -> DeviceStatus: ...

    def inputs(self) -> Mapping[str, Input]: ...

    def input(self, name: str) -> Input:
        """One input by name; the error names the device and what is allowed."""
        ...

    def faults(self) -> Mapping[str, Fault]: ...

    def fault(self, name: str) -> Fault:
        """One fault by name; the error names the device and what is allowed."""
        ...

    def outputs(self) -> Mapping[str, Output]:
        """Every output the device drives (none for an input-only device)."""
        ...

    def streams(self) -> Sequence[Stream]:
        """What the device publishes as it happens (none for most)."""
        ...

    def objects(self) -> Objects: ...

    def ports(self) -> list[Port]: ...

    def panel(self) -> FrontPanel:
        """The front, typed: LEDs, bit rows, words, readings, frozen values, log."""
        ...


def allowed_names(names: list[str]) -> str:
    """``0..7``, ``0..15, a0..a3``, ``0, 1, 0.CTS``: runs of numbered names as ranges."""
    parts: list[str] = []
    run: list[tuple[str, int]] = []  # (prefix, number) of the current run

    def flush() -> None:
        if run:
            (prefix, first), (_, last) = run[0], run[-1]
            text = f"{prefix}{first}..{prefix}{last}" if last - first > 1 else None
            parts.extend([text] if text else [f"{p}{n}" for p, n in run])
            run.clear()

    for name in names:
        prefix, digits = name.rstrip("0123456789"), name[len(name.rstrip("0123456789")) :]
        if (
            digits
            and prefix in ("", "a")
            and (not run or (run[-1][0] == prefix and run[-1][1] + 1 == int(digits)))
        ):
            run.append((prefix, int(digits)))
            continue
        flush()
        if digits and prefix in ("", "a"):
            run.append((prefix, int(digits)))
        else:
            parts.append(name)
    flush()
    return ", ".join(parts) or "none"


def pick_input(device: Device, name: str) -> Input:
    """The input ``name`` of ``device``; the error lists what is allowed."""
    inputs = device.inputs()
    found = inputs.get(name.strip()) or inputs.get(name.strip().lower())
    if found is None:
        allowed = allowed_names(list(inputs))
        raise ConfigError(f"{device.kind} {device.address}: no input {name!r} (allowed: {allowed})")
    return found


class FaultNotApplicable(ConfigError):
    """A line fault none of the device's ports can carry (answered 400, not 404)."""


def applies(fault: Fault, ports: Sequence[Port]) -> bool:
    """A device fault always applies; a line fault where one of ``ports`` is of its kinds."""
    return not fault.port_kinds or any(fault.name in p.kind.line_faults for p in ports)


def applicable(faults: Mapping[str, Fault], ports: Sequence[Port]) -> dict[str, Fault]:
    """The faults of ``faults`` that apply to a device with ``ports`` (what ``faults()`` gives)."""
    return {name: f for name, f in faults.items() if applies(f, ports)}


def refuse_inapplicable(device: Device, fault: Fault) -> None:
    """A line fault none of the device's ports carries: refused, naming where it applies."""
    ports = device.ports()
    if applies(fault, ports):
        return
    has = ", ".join(dict.fromkeys(p.kind.name for p in ports)) or "no port"
    raise FaultNotApplicable(
        f"fault {fault.name!r} does not apply to {device.kind} {device.address}: it applies"
        f" to ports of kind {' or '.join(fault.port_kinds)}; this device has {has}"
    )


def pick_fault(device: Device, name: str, every: Mapping[str, Fault] | None = None) -> Fault:
    """The fault ``name`` of ``device``; ``every`` (all its kind's faults, whatever its
    ports) tells a line fault that does not apply here from an unknown name."""
    faults = device.faults()
    found = faults.get(name.strip())
    if found is None and every is not None and name.strip() in every:
        refuse_inapplicable(device, every[name.strip()])
    if found is None:
        allowed = ", ".join(faults) or "none"
        raise ConfigError(
            f"unknown fault {name!r} for {device.kind} {device.address} (allowed: {allowed})"
        )
    return found


def active_faults(faults: Mapping[str, Fault]) -> tuple[ActiveFault, ...]:
    """The faults of ``faults`` in force, with their parameters (for ``DeviceStatus``)."""
    found = []
    for fault in faults.values():
        params = fault.in_force()
        if params is not None:
            found.append(ActiveFault(fault.name, dict(params)))
    return tuple(found)


def read_outputs(outputs: Mapping[str, Output]) -> tuple[OutputValue, ...]:
    return tuple(o.read() for o in outputs.values())


def device_id(device: Device, devices: Sequence[Device]) -> str:
    """A device's id in the control API and the test helpers: ``5`` / ``23`` for a
    module; ``tes1`` for a TES (``tes1@2`` when slave 1 answers on several
    endpoints: the second endpoint in file order).  Each address says its own."""
    return device.address.ident([d.address for d in devices])


# --- the front panel ---------------------------------------------------------------

PanelValue = bool | int | float | str | None


@dataclass(frozen=True, slots=True)
class Reading:
    """A value the front shows: a measurement in its unit (an AEM channel in its
    scaling, a TES analog input in volts), with flags such as ``"overflow"`` or a
    channel fault, the line a person reads, and the kind's other facts beside
    (``range``, ``points``...)."""

    name: str
    value: float | int | None  # None: nothing to show (an inhibited channel)
    unit: str = ""
    flags: tuple[str, ...] = ()
    text: str = ""
    more: tuple[tuple[str, PanelValue], ...] = ()


@dataclass(frozen=True, slots=True)
class BitRow:
    """A row of bits on the front (a TES's inputs, its outputs), bit 0 first."""

    name: str
    bits: tuple[bool, ...]


@dataclass(frozen=True, slots=True)
class PanelWord:
    """A word the front shows as a number (a TES's watchdog word); None: unreadable."""

    name: str
    value: int | None


@dataclass(frozen=True, slots=True)
class Logged:
    """One item a device logged (a DEM's stacked message), formatted once, here."""

    stamp: str  # "1994-07-15 10:00:00.120"
    kind: str  # "change", "overall"
    text: str  # "input 3 -> 1"
    flags: tuple[str, ...] = ()  # "H": the message carries the H bit (DEM 4.2-2)


@dataclass(frozen=True, slots=True)
class FrontPanel:
    """What a device's front shows, typed: every window renders it, none parses it.

    ``fields`` are the kind's other facts by name (``time``, ``fill``, ``logging``);
    ``frozen`` the values a device holds until they are read or cleared (a TES's
    edge counters); ``log`` the newest items it logged, newest first."""

    leds: tuple[tuple[str, LedState], ...]
    bits: tuple[BitRow, ...] = ()
    words: tuple[PanelWord, ...] = ()
    readings: tuple[Reading, ...] = ()
    frozen: tuple[Reading, ...] = ()
    fields: tuple[tuple[str, PanelValue], ...] = ()
    log: tuple[Logged, ...] = ()

    def field(self, name: str, default: PanelValue = None) -> PanelValue:
        return dict(self.fields).get(name, default)

    def row(self, name: str) -> tuple[bool, ...]:
        return next((r.bits for r in self.bits if r.name == name), ())

    def word(self, name: str) -> int | None:
        return next((w.value for w in self.words if w.name == name), None)

    def lines(self) -> list[str]:
        """The front as text, one line per part, for the console and the live view:
        ``in: 0000000000001000 (15..0)``, ``watchdog: H'0000'``, ``readings: 0=2.000V
        1=- [overflow]``, ``frozen: 0=3rises``, ``log: 2 items, newest ...``.  The
        LEDs and the fields are left to the status line and the details."""
        out = [
            f"{r.name}: {''.join('1' if b else '0' for b in reversed(r.bits))}"
            f" ({len(r.bits) - 1}..0)"
            for r in self.bits
            if r.bits
        ]
        out.extend(
            f"{w.name}: {'-' if w.value is None else format_hex(w.value & 0xFFFF)}"
            for w in self.words
        )
        if self.readings:
            out.append("readings: " + " ".join(reading_text(r) for r in self.readings))
        if self.frozen:
            out.append("frozen: " + " ".join(reading_text(r) for r in self.frozen))
        if self.log:
            newest = self.log[0]
            out.append(f"log: {len(self.log)} shown, newest {newest.stamp} {newest.text}")
        return out


def reading_text(reading: Reading) -> str:
    """``0=2.000V``, ``3=12 rises``, ``1=- [inhibited]``, ``2=11.2 [overflow]``: a
    unit of a word or more stands apart."""
    value = reading.value
    unit = reading.unit if len(reading.unit) <= 2 else f" {reading.unit}"
    if value is None:
        shown = "-"
    elif isinstance(value, float):
        shown = f"{value:.3f}{unit}"
    else:
        shown = f"{value}{unit}"
    flags = f" [{','.join(reading.flags)}]" if reading.flags else ""
    return f"{reading.name}={shown}{flags}"


def watching(publish: Publish) -> Callable[[], bool]:
    """Whether anyone looks at what ``publish`` receives now: its ``active`` where the
    subscriber tells (the runtime's event bus), else always (a stream may skip its
    work while nobody looks)."""
    active = getattr(publish, "active", None)
    if active is None:
        return lambda: True
    return lambda: bool(getattr(publish, "active", True))


# --- ports by kind: how the runtime opens a port -----------------------------------

SHARED_MODBUS = "modbus"  # slaves served on one endpoint, shared by every port naming it
OWN_LINE = "scm"  # a port that opens its own line (an SCM channel; the name recordings keep)


@dataclass(frozen=True, slots=True)
class ModbusSlave:
    """What a port of group SHARED_MODBUS gives the runtime to serve on its endpoint.

    ``line`` is the character format the device is set to (a serial endpoint
    without its own settings runs at it; every slave of the line must agree on
    speed and parity), ``settings`` says where a user changes them;
    ``wire_timing`` asks for the line's real character timing; ``drop_connections``
    receives the endpoint's function that closes its TCP connections while it is
    served, None when it closes."""

    slave: SlaveDevice
    link: Link
    name: str  # "TES 1 TES 32EST": as errors name it
    line: CharFormat
    settings: str  # "rs485.baud / rs485.parity; change them with `fieldtwin tesis`"
    what: str = "the device"  # "the TES": as errors call it
    wire_timing: bool = False
    drop_connections: Callable[[Callable[[], int] | None], None] | None = None
    strict_line: bool = True  # a pty master at other settings gets no answer (issue 23)


@dataclass(frozen=True, slots=True)
class Opened:
    """A port a device opened itself: its 'listening: ...' lines and how to close it."""

    lines: tuple[str, ...]
    close: Callable[[], None]
