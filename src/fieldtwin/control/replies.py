"""The answers of the control API: one pydantic model per answer's shape.

The server's routes declare them (so ``/openapi.json`` describes every answer) and
``fieldtwin.client`` parses what it receives with the same models.  A key that an
answer gives only sometimes (``description`` of an output, ``power`` of a clock
event) is optional and left out when absent (the routes answer with
``exclude_unset``): every body is exactly what docs/control.md shows.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, RootModel

Scalar = bool | int | float | str | None


class Reply(BaseModel):
    """An answer's model: its keys as documented; none dropped if the plant adds one."""

    model_config = ConfigDict(extra="allow")


# --- the clock ---------------------------------------------------------------------


class ClockState(Reply):
    """Simulated time, paused or not, the speed factor and the runner mode in progress."""

    t_s: float
    t_us: int
    paused: bool
    speed: float | Literal["max"]
    mode: str | None
    until_s: float | None


class ClockJson(ClockState):
    """``GET /clock``: the state and the speed reached on the wall."""

    speed_reached: float | None
    speed_kept: bool


class ClockEvent(ClockState):
    """A clock command's answer (the clock event it published): a power break's
    ``power`` (off, back) and, at a mode's end, ``cut`` (the mode was cut short)."""

    power: str | None = None
    cut: bool | None = None


# --- the plant and its devices -------------------------------------------------------


class PlcState(Reply):
    mode: str
    fault: str | None


class DeviceEntry(Reply):
    id: str
    kind: str
    family: str
    address: str
    state: str


class PlantJson(Reply):
    """``GET /plant``."""

    title: str
    name: str
    clock: ClockJson
    plc: PlcState | None
    devices: list[DeviceEntry]


class PortJson(Reply):
    name: str
    line: str


class OutputJson(Reply):
    """One output: its value in the device's units (a bit: true/false), the raw word."""

    name: str
    description: str | None = None
    value: bool | float
    unit: str
    raw: int | None
    text: str


class StatusJson(Reply):
    """``GET /devices/{ident}``."""

    id: str
    kind: str
    address: str
    state: str
    mode: str | None
    leds: dict[str, str]
    ports: list[PortJson]
    details: dict[str, str]
    active_faults: dict[str, dict[str, int | float]]
    outputs: list[OutputJson]


Leds = RootModel[dict[str, str]]


class InputJson(Reply):
    name: str
    description: str
    signal: bool


class InputSet(Reply):
    """An input set to a value, or driven by a signal table."""

    device: str
    input: str
    value: bool | int | float | str | None = None
    signal: dict[str, object] | None = None


class FaultJson(Reply):
    name: str
    description: str
    active: bool
    params: dict[str, int | float]
    takes: list[str]
    hint: str


class FaultSet(Reply):
    device: str
    fault: str
    active: bool
    params: dict[str, int | float]


class ObjectValue(Reply):
    """An object's value (a 16-bit word) and its hexadecimal text."""

    device: str
    object: str
    value: int
    hex: str


class PowerCycled(Reply):
    device: str
    power: str  # "cycled" (at once), or "off" until back_at_s (an outage that lasts)
    back_at_s: float | None = None


# --- the PLC -------------------------------------------------------------------------


class ExchangeJson(Reply):
    """A Text Block exchange: its state, and its result once done (``V``/``S``/``E``,
    the report under its own name, the words, the bytes in hex, when it ended)."""

    id: int
    txt: int
    m: str
    c: str
    state: str
    done: bool
    result: dict[str, Scalar | list[int]] | None


class ModuleJson(Reply):
    module: str
    present: bool


# --- the console and the dashboard --------------------------------------------------------


class ConsoleAnswer(Reply):
    """A console line's output lines, or its error."""

    lines: list[str]
    error: str | None


class DashboardState(Reply):
    """What the dashboard draws: the clock, the PLC and its modules, the TES
    terminals (docs/dashboard.md; each panel as fieldtwin.control.panels builds it)."""

    title: str
    clock: ClockJson
    plc: dict[str, object] | None
    modules: list[dict[str, object]]
    tes: list[dict[str, object]]


__all__ = [
    "ClockEvent",
    "ClockJson",
    "ClockState",
    "ConsoleAnswer",
    "DashboardState",
    "DeviceEntry",
    "ExchangeJson",
    "FaultJson",
    "FaultSet",
    "InputJson",
    "InputSet",
    "Leds",
    "ModuleJson",
    "ObjectValue",
    "OutputJson",
    "PlantJson",
    "PlcState",
    "PortJson",
    "PowerCycled",
    "Reply",
    "StatusJson",
]
