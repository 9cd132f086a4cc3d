"""Reading a plant file: TOML -> a validated description (no device is built).

``read_plant`` parses the file and checks its top-level tables; ``describe``
checks what can be checked without building anything: ``[plant]``, ``[plc]``
(model, scan, watchdog, the known keys), and every ``[[module]]`` / ``[[tes]]``
table against its kind's schema (fieldtwin.devices: one registry of kinds, one
schema each).  Every error names the file and the field path:
``plant.toml: module[1].slot: ...``.  What needs the built PLC (its program,
constants, initial outputs) is checked by the builder (fieldtwin.plant.building).
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from fieldtwin.devices import registry
from fieldtwin.devices.face import Family
from fieldtwin.devices.kind import DeviceKind
from fieldtwin.devices.schema import Table, table_at
from fieldtwin.errors import ConfigError
from fieldtwin.runtime.pace import MAX_SPEED, MIN_SPEED
from fieldtwin.textfile import read_text
from fieldtwin.tsx.plc import MODELS, WATCHDOG_MS, WATCHDOG_RANGE_MS

if TYPE_CHECKING:
    from fieldtwin.runtime.record import Header

DEFAULT_PLANT = "default.toml"
DEFAULT_NAME = "<default plant>"
TOP_LEVEL = ("plant", "plc", "module", "tes", "run", "tag", "dashboard")
PROGRAM_KEYS = ("program", "constants", "text_blocks", "date", "watch")

MAX_PLANT_BYTES = 4 * 1024 * 1024  # a plant file is read whole: bounded (DESIGN rule 14)
MAX_EMBEDDED_BYTES = MAX_PLANT_BYTES  # one file a plant names, embedded in a recording


@dataclass(frozen=True, slots=True)
class PlantFile:
    """A parsed, not yet built, plant file."""

    name: str  # what errors call it: the path, or "<default plant>"
    data: Mapping[str, object]
    base_dir: Path
    text: str = ""  # the file as read (a recording embeds it)


@dataclass(frozen=True, slots=True)
class PlcDescription:
    """``[plc]`` checked: what the PLC is built with, and the keys applied once it is."""

    model: str
    scan_ms: int | float
    watchdog_ms: int | float
    outputs: object  # the ``outputs`` table (checked against the built PLC)
    program: Mapping[str, object]  # PROGRAM_KEYS given (checked against the built PLC)


@dataclass(frozen=True, slots=True)
class DeviceDescription:
    """One ``[[module]]`` or ``[[tes]]`` table: its kind and its schema-checked table."""

    family: Family
    kind: DeviceKind
    table: Table
    where: str  # "plant.toml: module[1]": the field path of its errors


@dataclass(frozen=True, slots=True)
class PlantDescription:
    """A plant file checked and ready to build (fieldtwin.plant.building)."""

    source: PlantFile
    title: str
    plc: PlcDescription | None  # None: a plant of TES only
    devices: tuple[DeviceDescription, ...]  # in file order: modules, then TES

    @property
    def name(self) -> str:
        return self.source.name


def read_plant(path: str | Path | None) -> PlantFile:
    """Parse a plant file, or the embedded default plant when ``path`` is None."""
    if path is None:
        text = resources.files("fieldtwin").joinpath("plants", DEFAULT_PLANT).read_text("utf-8")
        return parse(text, DEFAULT_NAME, Path.cwd())
    p = Path(path)
    text = read_text(p, MAX_PLANT_BYTES, "plant file")  # regular files only: never blocks
    return parse(text, str(p), p.resolve().parent)


def parse(text: str, name: str, base_dir: Path) -> PlantFile:
    """The text of a plant file, parsed; ``name`` is what its errors call it."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{name}: not valid TOML: {exc}") from None
    except RecursionError:  # arrays or tables nested thousands deep
        raise ConfigError(f"{name}: nested too deeply (not a plant file)") from None
    unknown = sorted(set(data) - set(TOP_LEVEL))
    if unknown:
        raise ConfigError(
            f"{name}: unknown top-level key(s) {', '.join(unknown)}"
            f" (allowed: {', '.join(TOP_LEVEL)})"
        )
    return PlantFile(name, data, base_dir, text)


def describe(plant_file: PlantFile) -> PlantDescription:
    """The plant file checked: ``[plant]``, ``[plc]``, each device table's kind and keys."""
    data, name = plant_file.data, plant_file.name
    title = str(table_of(data, "plant", name).get("name", Path(name).stem))
    plc = _plc(plant_file)
    devices: list[DeviceDescription] = []
    for key, family in (("module", Family.MODULE), ("tes", Family.TES)):
        for index, table in enumerate(array_of(data, key, name)):
            devices.append(_device(table, family, f"{name}: {key}[{index}]"))
    return PlantDescription(plant_file, title, plc, tuple(devices))


def plant_speed(plant_file: PlantFile) -> float | None:
    """The speed factor of ``[run] speed`` (1 when absent; None for "max")."""
    name = plant_file.name
    run = table_of(plant_file.data, "run", name)
    if set(run) - {"speed"}:
        raise ConfigError(
            f"{name}: run: unknown key(s) {', '.join(sorted(set(run) - {'speed'}))}"
            " (allowed: speed)"
        )
    return speed_value(run.get("speed", 1.0), f"{name}: run.speed")


def speed_value(value: object, where: str) -> float | None:
    """A speed factor as a plant file gives it (a number in range, or "max": None)."""
    if value == "max":
        return None
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if not number or not MIN_SPEED <= value <= MAX_SPEED:  # type: ignore[operator]
        raise ConfigError(
            f"{where}: {value!r} not allowed (allowed a number from {MIN_SPEED:g}"
            f' to {MAX_SPEED:g}, or "max")'
        )
    return float(value)  # type: ignore[arg-type]


def table_of(data: Mapping[str, object], key: str, name: str) -> Mapping[str, object]:
    value = data.get(key, {})
    if not isinstance(value, Mapping):
        raise ConfigError(f"{name}: {key} must be a table ([{key}])")
    return value


def array_of(data: Mapping[str, object], key: str, name: str) -> list[object]:
    tables = data.get(key, [])
    if not isinstance(tables, list):
        raise ConfigError(f"{name}: {key} must be an array of tables ([[{key}]])")
    return tables


def _plc(plant_file: PlantFile) -> PlcDescription | None:
    """``[plc]`` (or the default PLC of a plant with modules), its keys checked."""
    data, name = plant_file.data, plant_file.name
    modules = array_of(data, "module", name)
    if "plc" not in data and not modules:
        return None
    plc_table = dict(table_of(data, "plc", name))
    model = plc_table.pop("model", "TSX 87")
    if not isinstance(model, str) or model not in MODELS:
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
    watchdog_ms = plc_table.pop("watchdog_ms", WATCHDOG_MS)
    low, high = WATCHDOG_RANGE_MS
    if (
        isinstance(watchdog_ms, bool)
        or not isinstance(watchdog_ms, int | float)
        or not low <= watchdog_ms <= high
    ):
        raise ConfigError(
            f"{name}: plc.watchdog_ms: {watchdog_ms!r} not allowed (allowed {low}..{high} ms)"
        )
    outputs = plc_table.pop("outputs", {})
    keys = {k: plc_table.pop(k) for k in PROGRAM_KEYS if k in plc_table}
    if plc_table:
        raise ConfigError(
            f"{name}: plc: unknown key(s) {', '.join(sorted(plc_table))}"
            " (allowed: model, scan_ms, outputs), watchdog_ms"
            f" and, for a program, {', '.join(PROGRAM_KEYS)}"
        )
    return PlcDescription(model, scan_ms, watchdog_ms, outputs, keys)


def _device(table: object, family: Family, where: str) -> DeviceDescription:
    """One table -> its kind, and the table checked against the kind's schema."""
    key = "type" if family is Family.MODULE else "model"
    checked = table_at(table, where)
    kind_name = checked.get(key)
    if not isinstance(kind_name, str):
        example = '"TSX AEM 811"' if family is Family.MODULE else "TES 16EST, TES 8EA, ..."
        if family is Family.MODULE:
            raise ConfigError(f"{where}.type: missing or not a string (e.g. {example})")
        raise ConfigError(f"{where}.model: missing (allowed: {example})")
    try:
        kind = registry.kind_named(kind_name, family)
    except ConfigError as exc:
        raise ConfigError(f"{where}.{key}: {exc}") from None
    return DeviceDescription(family, kind, kind.schema.check(checked, where, kind.name), where)


# ----------------------------------------------------------- a plant file in a recording


def recording_header(plant_file: PlantFile, speed: float | None) -> Header:
    """A recording's header: the plant file's text and the files it names (docs/record.md)."""
    from fieldtwin.runtime.record import SAMPLE_MS, Header

    files: dict[str, str] = {}
    for value in _strings(plant_file.data):
        content = _named_file(plant_file, value)
        if content is not None:
            files[value] = content.decode("latin-1")
    return Header(plant_file.name, plant_file.text, files, speed, SAMPLE_MS)


def embedded_plant(header: Header, where: str, directory: Path) -> PlantFile:
    """The plant a recording embeds, its files written into ``directory`` (a replay's)."""
    plant_file = parse(header.plant_text, f"{where}: plant {header.plant_name}", directory)
    names: dict[str, str] = {}
    for index, (name, content) in enumerate(sorted(header.files.items())):
        target = directory / f"{index}-{Path(name).name or 'file'}"
        target.write_bytes(content.encode("latin-1"))
        names[name] = target.name
    data = _renamed(plant_file.data, names)
    assert isinstance(data, Mapping)
    return PlantFile(plant_file.name, data, directory, header.plant_text)


def _strings(value: object) -> list[str]:
    if isinstance(value, str):
        return [value]
    if isinstance(value, Mapping):
        return [s for v in value.values() for s in _strings(v)]
    if isinstance(value, list):
        return [s for v in value for s in _strings(v)]
    return []


def _named_file(plant_file: PlantFile, value: str) -> bytes | None:
    """The content of the file ``value`` names (relative to the plant file), if it does."""
    if not value or len(value) > 4096 or "\0" in value or "://" in value:
        return None
    embedded = resources.files("fieldtwin").joinpath("plants", Path(value).name)
    if plant_file.name == DEFAULT_NAME:
        return embedded.read_bytes() if embedded.is_file() else None
    path = plant_file.base_dir / value
    try:
        if path.is_file() and path.stat().st_size <= MAX_EMBEDDED_BYTES:
            return path.read_bytes()
    except (OSError, ValueError):
        return None
    if value.endswith(".pl7") and embedded.is_file():
        return embedded.read_bytes()
    return None


def _renamed(value: object, names: Mapping[str, str]) -> object:
    if isinstance(value, str):
        return names.get(value, value)
    if isinstance(value, Mapping):
        return {k: _renamed(v, names) for k, v in value.items()}
    if isinstance(value, list):
        return [_renamed(v, names) for v in value]
    return value
