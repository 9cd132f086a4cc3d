"""A plant file (TOML) -> a PLC with its modules, TES terminals, signals and endpoints.

Fixed keys (tests outside the project rely on them)::

    [plc]
    model = "TSX 87"
    scan_ms = 10

    [[module]]
    type = "TSX AEM 811"
    rack = 0
    slot = 5

    [[tes]]
    model = "TES 32EST"
    slave = 1
    endpoint = "tcp://127.0.0.1:5020"

Every other key of a ``[[module]]`` table goes to that module's
``configure_from_plant``; ``[[tes]]`` tables go to ``fieldtwin.tes.plant``.
Errors name the file and the field path: ``plant.toml: module[1].slot: ...``.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from fieldtwin.clock import SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.tsx.plc import MODELS, Plc

DEFAULT_PLANT = "default.toml"
FROM_PLANT = "from plant"  # build_plant(speed=FROM_PLANT): take [run] speed
TOP_LEVEL = ("plant", "plc", "module", "tes", "run")


@dataclass(frozen=True, slots=True)
class PlantFile:
    """A parsed, not yet built, plant file."""

    name: str  # what errors call it: the path, or "<default plant>"
    data: Mapping[str, Any]
    base_dir: Path


@dataclass(slots=True)
class Plant:
    """A plant brought to life (in simulated time; `fieldtwin run` paces it)."""

    name: str
    title: str
    clock: SimClock
    plc: Plc | None
    tes: list[Any] = field(default_factory=list)
    tes_tables: list[Mapping[str, Any]] = field(default_factory=list)
    servers: list[Any] = field(default_factory=list)
    speed: float | None = 1.0

    def tes_by_slave(self, slave: int) -> Any:
        found = [t for t in self.tes if t.slave == slave]
        if not found:
            have = ", ".join(str(t.slave) for t in self.tes) or "none"
            raise ConfigError(f"no TES with slave number {slave} in this plant (have: {have})")
        return found[0]

    def start_endpoints(self, runner: Any) -> list[str]:
        """Open the TES Modbus endpoints; returns one 'listening: ...' line each."""
        if not self.tes:
            return []
        from fieldtwin.tes.plant import start_tes_endpoints

        self.servers = list(start_tes_endpoints(self.tes, self.tes_tables, runner))
        return [server.describe() for server in self.servers]

    def close(self) -> None:
        for server in self.servers:
            server.close()
        self.servers.clear()


def read_plant(path: str | Path | None) -> PlantFile:
    """Parse a plant file, or the embedded default plant when ``path`` is None."""
    if path is None:
        text = resources.files("fieldtwin").joinpath("plants", DEFAULT_PLANT).read_text("utf-8")
        return _parse(text, "<default plant>", Path.cwd())
    p = Path(path)
    try:
        text = p.read_text("utf-8")
    except OSError as exc:
        raise ConfigError(f"{p}: cannot read the plant file ({exc.strerror})") from None
    return _parse(text, str(p), p.resolve().parent)


def _parse(text: str, name: str, base_dir: Path) -> PlantFile:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{name}: not valid TOML: {exc}") from None
    unknown = sorted(set(data) - set(TOP_LEVEL))
    if unknown:
        raise ConfigError(
            f"{name}: unknown top-level key(s) {', '.join(unknown)}"
            f" (allowed: {', '.join(TOP_LEVEL)})"
        )
    return PlantFile(name, data, base_dir)


def build_plant(
    plant_file: PlantFile,
    *,
    clock: SimClock | None = None,
    runner: Any = None,
    speed: float | str | None = FROM_PLANT,
) -> Plant:
    """Build the PLC, modules and TES of a plant file (endpoints are opened later).

    ``speed``: a factor, None for as fast as possible, or FROM_PLANT for ``[run] speed``.
    """
    data, name = plant_file.data, plant_file.name
    clock = clock or (runner.clock if runner is not None else SimClock())
    pace = plant_speed(plant_file) if speed == FROM_PLANT else speed
    assert not isinstance(pace, str)
    title = str(_table(data, "plant", name).get("name", Path(name).stem))
    plc = _build_plc(plant_file, clock, runner, pace)
    plant = Plant(name, title, clock, plc, speed=pace)
    tes_tables = data.get("tes", [])
    if not isinstance(tes_tables, list):
        raise ConfigError(f"{name}: tes must be an array of tables ([[tes]])")
    if tes_tables:
        from fieldtwin.tes.plant import build_tes

        plant.tes = list(build_tes(tes_tables, clock, name, plant_file.base_dir))
        plant.tes_tables = tes_tables
    return plant


def plant_speed(plant_file: PlantFile) -> float | None:
    """The speed factor of ``[run] speed`` (1 when absent; None for "max")."""
    name = plant_file.name
    run = _table(plant_file.data, "run", name)
    if set(run) - {"speed"}:
        raise ConfigError(
            f"{name}: run: unknown key(s) {', '.join(sorted(set(run) - {'speed'}))}"
            " (allowed: speed)"
        )
    return _speed(run.get("speed", 1.0), f"{name}: run.speed")


def load_plant(path: str | Path | None = None, **kwargs: Any) -> Plant:
    return build_plant(read_plant(path), **kwargs)


def _table(data: Mapping[str, Any], key: str, name: str) -> Mapping[str, Any]:
    value = data.get(key, {})
    if not isinstance(value, Mapping):
        raise ConfigError(f"{name}: {key} must be a table ([{key}])")
    return value


def _speed(value: Any, where: str) -> float | None:
    if value == "max":
        return None
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if not number or not 0 < value < math.inf:
        raise ConfigError(f'{where}: {value!r} not allowed (allowed a number > 0, or "max")')
    return float(value)


def _build_plc(
    plant_file: PlantFile, clock: SimClock, runner: Any, speed: float | None
) -> Plc | None:
    data, name = plant_file.data, plant_file.name
    modules = data.get("module", [])
    if not isinstance(modules, list):
        raise ConfigError(f"{name}: module must be an array of tables ([[module]])")
    if "plc" not in data and not modules:
        return None
    plc_table = dict(_table(data, "plc", name))
    model = plc_table.pop("model", "TSX 87")
    if model not in MODELS:
        raise ConfigError(
            f"{name}: plc.model: {model!r} not allowed (allowed: {', '.join(MODELS)})"
        )
    scan_ms = plc_table.pop("scan_ms", 10)
    if (
        isinstance(scan_ms, bool)
        or not isinstance(scan_ms, int | float)
        or not 1 <= scan_ms <= 1000
    ):
        raise ConfigError(f"{name}: plc.scan_ms: {scan_ms!r} not allowed (allowed 1..1000 ms)")
    outputs = plc_table.pop("outputs", {})
    if plc_table:
        raise ConfigError(
            f"{name}: plc: unknown key(s) {', '.join(sorted(plc_table))}"
            " (allowed: model, scan_ms, outputs)"
        )
    plc = Plc(model=model, scan_ms=scan_ms, clock=clock, runner=runner, speed=speed)
    for index, table in enumerate(modules):
        _insert(plc, table, f"{name}: module[{index}]", plant_file.base_dir)
    _initial_outputs(plc, outputs, f"{name}: plc.outputs")
    return plc


def _initial_outputs(plc: Plc, outputs: Any, where: str) -> None:
    """``[plc] outputs = { "OW5,0,C" = 1 }``: what the PLC program writes from the start."""
    if not isinstance(outputs, Mapping):
        raise ConfigError(f'{where}: must be a table of objects, e.g. {{ "OW5,0,C" = 1 }}')
    for obj, value in outputs.items():
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{where}.{obj!r}: {value!r} is not an integer")
        try:
            plc.write(obj, value)
        except ConfigError as exc:
            raise ConfigError(f"{where}.{obj!r}: {exc}") from None


def _int_field(table: Mapping[str, Any], key: str, where: str, default: int | None = None) -> int:
    value = table.get(key, default)
    if value is None:
        raise ConfigError(f"{where}.{key}: missing (an integer is required)")
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(f"{where}.{key}: {value!r} is not an integer")
    return value


def _insert(plc: Plc, table: Any, where: str, base_dir: Path) -> None:
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: must be a table")
    rest = dict(table)
    type_name = rest.pop("type", None)
    if not isinstance(type_name, str):
        raise ConfigError(f'{where}.type: missing or not a string (e.g. "TSX AEM 811")')
    rack = _int_field(rest, "rack", where, 0)
    slot = _int_field(rest, "slot", where)
    code = rest.get("code")
    code = None if code is None else _int_field(rest, "code", where)
    for key in ("rack", "slot", "code"):
        rest.pop(key, None)
    try:
        module = plc.insert(type_name, rack=rack, slot=slot, code=code)
    except ConfigError as exc:
        text = str(exc)
        field_name = "type" if "module type" in text else "rack" if "rack" in text else "slot"
        raise ConfigError(f"{where}.{field_name}: {exc}") from None
    try:
        module.configure_from_plant(rest, where, base_dir)
    except ConfigError as exc:
        message = str(exc)
        raise ConfigError(message if message.startswith(where) else f"{where}: {message}") from None
