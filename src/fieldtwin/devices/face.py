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

import enum
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from fieldtwin.errors import ConfigError

InputValue = bool | float | str  # a contact, a value in the input's unit, or console text
SignalSpec = Mapping[str, object]  # a plant-file signal table: { kind = "sine", ... }
LedState = str  # "on", "off" or "blink"


class Family(enum.Enum):
    MODULE = "module"  # a TSX intelligent module in a rack slot
    TES = "tes"  # a Leroy TES remote I/O terminal on a Modbus endpoint


@dataclass(frozen=True, slots=True)
class ModuleAddress:
    """Rack and slot; written as the console writes it: ``5`` (rack 0) or ``23``."""

    rack: int
    slot: int

    def __str__(self) -> str:
        return f"{self.slot}" if self.rack == 0 else f"{self.rack}{self.slot}"


@dataclass(frozen=True, slots=True)
class TesAddress:
    """An endpoint and a slave number on it, as the console names it:
    ``tcp://127.0.0.1:5020 1`` (``tes tcp://127.0.0.1:5020 1 read H'000'``)."""

    endpoint: str
    slave: int

    def __str__(self) -> str:
        return f"{self.endpoint} {self.slave}"


Address = ModuleAddress | TesAddress


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


@dataclass(frozen=True, slots=True)
class Fault:
    """A named fault: described, set (with its parameters, if it takes any) and cleared.

    ``params`` names what ``set`` takes (a TES's ``late_answer`` takes ``ms``);
    ``configure`` receives them.  A fault without parameters has only ``setter``.
    """

    name: str
    description: str
    setter: Callable[[bool], None]
    params: tuple[str, ...] = ()
    configure: Callable[[bool, Mapping[str, FaultParam]], None] | None = None

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


class Objects(Protocol):
    """What a master reads and writes: PL7 objects of a module, registers of a TES."""

    def names(self) -> list[str]: ...

    def read(self, name: str) -> int:
        """A master's read, with its side effects (a TES's memorized inputs...)."""
        ...

    def peek(self, name: str) -> int:
        """The value as it stands, without side effects."""
        ...

    def write(self, name: str, value: int) -> None: ...


@dataclass(frozen=True, slots=True)
class Port:
    """What the runtime may bind: an endpoint URL and the function that opens it."""

    name: str
    endpoint: str
    group: str  # ports with the same group and endpoint share one line ("modbus", "scm")


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

    def objects(self) -> Objects: ...

    def ports(self) -> list[Port]: ...


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


def pick_fault(device: Device, name: str) -> Fault:
    faults = device.faults()
    found = faults.get(name.strip())
    if found is None:
        allowed = ", ".join(faults) or "none"
        raise ConfigError(
            f"unknown fault {name!r} for {device.kind} {device.address} (allowed: {allowed})"
        )
    return found


def device_id(device: Device, devices: Sequence[Device]) -> str:
    """A device's id in the control API and the test helpers: ``5`` / ``23`` for a
    module; ``tes1`` for a TES (``tes1@2`` when slave 1 answers on several
    endpoints: the second endpoint in file order)."""
    address = device.address
    if not isinstance(address, TesAddress):
        return str(address)
    endpoints: list[str] = []
    for other in devices:
        a = other.address
        if isinstance(a, TesAddress) and a.slave == address.slave and a.endpoint not in endpoints:
            endpoints.append(a.endpoint)
    index = endpoints.index(address.endpoint)
    return f"tes{address.slave}" if index == 0 else f"tes{address.slave}@{index + 1}"
