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

Every ``[[module]]`` and ``[[tes]]`` table is checked against its kind's schema
(fieldtwin.devices: one registry of kinds, one schema each) and built with one
build context (clock, PLC, base directory); wiring between devices (a DEM's
sync output) is done once every device is in.  Endpoints are opened after the
plant is built, by the runtime's binder (fieldtwin.runtime.binder):
``load_plant`` binds the module ports (SCM channels), ``fieldtwin run`` binds
every port.  Errors name the file and the field path: ``plant.toml: module[1].slot: ...``.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import partial
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from fieldtwin.clock import SimClock
from fieldtwin.devices import registry
from fieldtwin.devices.context import BuildContext
from fieldtwin.devices.face import Device, Family, TesAddress
from fieldtwin.devices.module import ModuleDevice
from fieldtwin.devices.schema import table_at
from fieldtwin.errors import ConfigError
from fieldtwin.facade.tes import Tes, tes_core
from fieldtwin.runtime.door import Door
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.pace import MAX_SPEED, MIN_SPEED
from fieldtwin.textfile import read_text
from fieldtwin.tsx.bus import Host
from fieldtwin.tsx.plc import MAX_PROGRAM_BYTES, MODELS, WATCHDOG_MS, WATCHDOG_RANGE_MS, Plc
from fieldtwin.tsx.plcmemory import TxtDeclaration
from fieldtwin.words import plant_word

if TYPE_CHECKING:
    from fieldtwin.runtime.binder import Binding
    from fieldtwin.runtime.record import Header, Recorder
    from fieldtwin.runtime.runner import Runner

DEFAULT_PLANT = "default.toml"
DEFAULT_NAME = "<default plant>"
FROM_PLANT = "from plant"  # build_plant(speed=FROM_PLANT): take [run] speed
TOP_LEVEL = ("plant", "plc", "module", "tes", "run")

MAX_PLANT_BYTES = 4 * 1024 * 1024  # a plant file is read whole: bounded (DESIGN rule 14)


@dataclass(frozen=True, slots=True)
class PlantFile:
    """A parsed, not yet built, plant file."""

    name: str  # what errors call it: the path, or "<default plant>"
    data: Mapping[str, object]
    base_dir: Path
    text: str = ""  # the file as read (a recording embeds it)


@dataclass(slots=True)
class Plant:
    """A plant brought to life (in simulated time; `fieldtwin run` paces it)."""

    name: str
    title: str
    clock: SimClock
    plc: Plc | None
    devices: list[Device] = field(default_factory=list)  # in file order: modules, then TES
    speed: float | None = 1.0
    bindings: list[Binding] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # what devices said of the file's inputs
    events: EventBus = field(default_factory=EventBus)  # what windows onto the plant observe
    source: PlantFile | None = None  # the file it was built from (a recording embeds it)
    recorder: Recorder | None = None  # plant.record(FILE): what enters and leaves is written
    door: Door = field(default_factory=Door)  # every command from outside runs here
    bound: list[tuple[str, ...]] = field(default_factory=list)  # the binder groups opened

    # --- devices -----------------------------------------------------------

    @property
    def tes_devices(self) -> list[Device]:
        """The TES devices, in file order."""
        return [d for d in self.devices if d.family == Family.TES]

    @property
    def tes(self) -> list[Tes]:
        """The TES cores, in file order (Python users and tests reach them so)."""
        return [t for t in map(tes_core, self.tes_devices) if t is not None]

    def module_device(self, rack: int, slot: int) -> ModuleDevice:
        """The module in rack/slot (one inserted from Python gets the generic face)."""
        for device in self.devices:
            if isinstance(device, ModuleDevice) and (device.module.rack, device.module.slot) == (
                rack,
                slot,
            ):
                return device
        if self.plc is None:
            raise ConfigError("this plant has no PLC (add a [plc] table or [[module]] tables)")
        return ModuleDevice(self.plc.module(rack, slot), self.plc)

    def tes_device(self, slave: int, endpoint: str | None = None) -> Device:
        """The TES answering ``slave`` (on ``endpoint`` when given); two on different
        endpoints with that number need the endpoint."""
        found = [
            (d, a)
            for d in self.tes_devices
            if isinstance(a := d.address, TesAddress)
            and a.slave == slave
            and (endpoint is None or a.endpoint == endpoint)
        ]
        if len(found) == 1:
            return found[0][0]
        have = ", ".join(str(d.address) for d in self.tes_devices) or "none"
        if not found:
            where = f" on {endpoint}" if endpoint is not None else ""
            raise ConfigError(
                f"no TES with slave number {slave}{where} in this plant (have: {have})"
            )
        raise ConfigError(
            f"slave number {slave} answers on {len(found)} endpoints: name the endpoint,"
            f" e.g. tes {found[0][1].endpoint} {slave} ... (have: {have})"
        )

    def tes_by_slave(self, slave: int) -> Tes:
        """The TES core answering ``slave`` (plant.tes_device(slave) is its device)."""
        core = tes_core(self.tes_device(slave))
        if core is None:  # a family-TES device that is no fieldtwin TES
            raise ConfigError(f"slave number {slave} is no TES core of fieldtwin")
        return core

    # --- endpoints ------------------------------------------------------------

    def start_endpoints(self, runner: Runner) -> list[str]:
        """Open the TES Modbus endpoints; returns one 'listening: ...' line each."""
        from fieldtwin.runtime.binder import MODBUS, bind

        if self.recorder is not None and runner.tap is None:
            runner.set_tap(self.recorder)  # recorded since before the endpoints opened
        self.note_bound((MODBUS,))
        binding = bind(self.devices, runner, groups=(MODBUS,), events=self.events)
        self.bindings.append(binding)
        return binding.lines

    def note_bound(self, groups: tuple[str, ...]) -> None:
        """The binder is about to open ``groups`` (a recording replays that)."""
        self.bound.append(groups)
        if self.recorder is not None:
            self.recorder.bound(groups)

    def record(self, path: str | Path, runner: Runner | None = None) -> Recorder:
        """Record what enters and leaves the plant into ``path`` (docs/record.md), until
        ``plant.close()`` (or the recorder's ``close()``).  ``runner``: the one pumping
        the plant's endpoints (default: the PLC's).  Start it before the plant runs."""
        from fieldtwin.runtime.record import Recorder

        if self.recorder is not None:
            raise ConfigError(f"this plant is already recording into {self.recorder.path}")
        if self.clock.now or self.clock.fired:
            raise ConfigError(
                f"plant.record: start the recording before the plant runs (simulated time is"
                f" {self.clock.now / 1e6:g} s): a replay starts from the plant file at t = 0"
            )
        pacer = runner or (self.plc.runner if self.plc is not None else None)
        if self.source is None:
            raise ConfigError(
                "plant.record: this plant was not built from a plant file (build_plant,"
                " load_plant): a replay rebuilds the plant from its file"
            )
        header = recording_header(self.source, self.speed)
        recorder = Recorder(path, header, self.clock, self.devices, self.events, door=self.door)
        for groups in self.bound:
            recorder.bound(groups)
        if isinstance(pacer, _runner_type()):
            pacer.set_tap(recorder)
        self.recorder = recorder
        self.bindings.append(_closing(recorder.close))
        return recorder

    def close(self) -> None:
        for binding in self.bindings:
            binding.close()
        self.bindings.clear()
        self.recorder = None


def read_plant(path: str | Path | None) -> PlantFile:
    """Parse a plant file, or the embedded default plant when ``path`` is None."""
    if path is None:
        text = resources.files("fieldtwin").joinpath("plants", DEFAULT_PLANT).read_text("utf-8")
        return _parse(text, DEFAULT_NAME, Path.cwd())
    p = Path(path)
    text = read_text(p, MAX_PLANT_BYTES, "plant file")  # regular files only: never blocks
    return _parse(text, str(p), p.resolve().parent)


def _runner_type() -> type[Runner]:
    from fieldtwin.runtime.runner import Runner

    return Runner


def _closing(close: Callable[[], None]) -> Binding:
    from fieldtwin.runtime.binder import Binding

    binding = Binding()
    binding.add([], close)
    return binding


MAX_EMBEDDED_BYTES = MAX_PLANT_BYTES  # one file a plant names, embedded in a recording


def recording_header(plant_file: PlantFile, speed: float | None) -> Header:
    """A recording's header: the plant file's text and the files it names (docs/record.md)."""
    from fieldtwin.runtime.record import SAMPLE_MS, Header

    files: dict[str, str] = {}
    for value in _strings(plant_file.data):
        content = _named_file(plant_file, value)
        if content is not None:
            files[value] = content.decode("latin-1")
    return Header(plant_file.name, plant_file.text, files, speed, SAMPLE_MS)


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


def embedded_plant(header: Header, where: str, directory: Path) -> PlantFile:
    """The plant a recording embeds, its files written into ``directory`` (a replay's)."""
    plant_file = _parse(header.plant_text, f"{where}: plant {header.plant_name}", directory)
    names: dict[str, str] = {}
    for index, (name, content) in enumerate(sorted(header.files.items())):
        target = directory / f"{index}-{Path(name).name or 'file'}"
        target.write_bytes(content.encode("latin-1"))
        names[name] = target.name
    data = _renamed(plant_file.data, names)
    assert isinstance(data, Mapping)
    return PlantFile(plant_file.name, data, directory, header.plant_text)


def _renamed(value: object, names: Mapping[str, str]) -> object:
    if isinstance(value, str):
        return names.get(value, value)
    if isinstance(value, Mapping):
        return {k: _renamed(v, names) for k, v in value.items()}
    if isinstance(value, list):
        return [_renamed(v, names) for v in value]
    return value


def _parse(text: str, name: str, base_dir: Path) -> PlantFile:
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


def build_plant(
    plant_file: PlantFile,
    *,
    clock: SimClock | None = None,
    runner: Runner | None = None,
    speed: float | str | None = FROM_PLANT,
    host: Host | None = None,
) -> Plant:
    """Build the PLC, modules and TES of a plant file (no endpoint is opened).

    ``speed``: a factor, None for as fast as possible, or FROM_PLANT for ``[run] speed``.
    ``host``: what opens the lines its modules wire (default: fieldtwin.hosting's,
    real endpoints; a replay gives one with virtual backends).
    """
    data, name = plant_file.data, plant_file.name
    clock = clock or (runner.clock if runner is not None else SimClock())
    pace = plant_speed(plant_file) if speed == FROM_PLANT else speed
    assert not isinstance(pace, str)
    title = str(_table(data, "plant", name).get("name", Path(name).stem))
    plc, outputs, program_keys = _build_plc(plant_file, clock, runner, pace, host)
    ctx = BuildContext(clock, plc, plant_file.base_dir, name)
    for key, family in (("module", Family.MODULE), ("tes", Family.TES)):
        for index, table in enumerate(_array(data, key, name)):
            ctx.devices.append(_build_device(table, family, ctx, f"{name}: {key}[{index}]"))
    ctx.finish()
    if plc is not None:
        _initial_outputs(plc, outputs, f"{name}: plc.outputs")
        _program(plc, program_keys, plant_file)
    plant = Plant(name, title, clock, plc, list(ctx.devices), speed=pace, notes=list(ctx.notes))
    plant.source = plant_file
    if plc is not None:  # the watchdog's trip on the event stream (docs/control.md)
        plc.on_fault = partial(_publish_fault, plant.events)
    return plant


KIND_PLC = "plc"  # the event of the PLC going to its fault state


def _publish_fault(events: EventBus, now: int, reason: str) -> None:
    events.publish(now, KIND_PLC, "plc", {"mode": "FAULT", "fault": reason})


def _array(data: Mapping[str, object], key: str, name: str) -> list[object]:
    tables = data.get(key, [])
    if not isinstance(tables, list):
        raise ConfigError(f"{name}: {key} must be an array of tables ([[{key}]])")
    return tables


def _build_device(table: object, family: Family, ctx: BuildContext, where: str) -> Device:
    """One table -> one device of its kind (schema checked first)."""
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
    return kind.build(kind.schema.check(checked, where, kind.name), ctx, where)


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


def load_plant(
    path: str | Path | None = None,
    *,
    clock: SimClock | None = None,
    runner: Runner | None = None,
    speed: float | str | None = FROM_PLANT,
) -> Plant:
    """Read and build a plant, and open its module ports (SCM channels) through the binder.

    The TES Modbus endpoints stay closed until ``plant.start_endpoints(runner)``:
    the console and Python are the TES's master themselves.
    """
    from fieldtwin.runtime.binder import SERIAL_LINE, bind

    plant = build_plant(read_plant(path), clock=clock, runner=runner, speed=speed)
    try:
        plant.note_bound((SERIAL_LINE,))
        plant.bindings.append(
            bind(plant.devices, runner, groups=(SERIAL_LINE,), events=plant.events)
        )
    except BaseException:
        plant.close()
        raise
    return plant


def _table(data: Mapping[str, object], key: str, name: str) -> Mapping[str, object]:
    value = data.get(key, {})
    if not isinstance(value, Mapping):
        raise ConfigError(f"{name}: {key} must be a table ([{key}])")
    return value


def _speed(value: object, where: str) -> float | None:
    if value == "max":
        return None
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if not number or not MIN_SPEED <= value <= MAX_SPEED:  # type: ignore[operator]
        raise ConfigError(
            f"{where}: {value!r} not allowed (allowed a number from {MIN_SPEED:g}"
            f' to {MAX_SPEED:g}, or "max")'
        )
    return float(value)  # type: ignore[arg-type]


def _build_plc(
    plant_file: PlantFile,
    clock: SimClock,
    runner: Runner | None,
    speed: float | None,
    host: Host | None = None,
) -> tuple[Plc | None, object, dict[str, object]]:
    """The PLC of ``[plc]`` (or of a plant with modules), its ``outputs`` table and its
    program keys (``program``, ``constants``, ``text_blocks``)."""
    data, name = plant_file.data, plant_file.name
    modules = _array(data, "module", name)
    if "plc" not in data and not modules:
        return None, {}, {}
    plc_table = dict(_table(data, "plc", name))
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
    plc = Plc(
        model=model,
        scan_ms=scan_ms,
        clock=clock,
        runner=runner,
        speed=speed,
        watchdog_ms=watchdog_ms,
        host=host,
    )
    return plc, outputs, keys


PROGRAM_KEYS = ("program", "constants", "text_blocks", "date", "watch")
_TABLE_RE = re.compile(r"^(CW|W)(\d{1,4})$", re.IGNORECASE)


def _program(plc: Plc, keys: Mapping[str, object], plant_file: PlantFile) -> None:
    try:
        _program_keys(plc, keys, plant_file)
    except ConfigError as exc:
        text, where = str(exc), f"{plant_file.name}: plc"
        raise ConfigError(
            text if text.startswith(plant_file.name) else f"{where}: {text}"
        ) from None


def _program_keys(plc: Plc, keys: Mapping[str, object], plant_file: PlantFile) -> None:
    """``constants`` (CW words), ``text_blocks`` (how TXTi's tables are declared), then
    ``program``: the PL7-3 file, relative to the plant file (docs/plant.md)."""
    where = f"{plant_file.name}: plc"
    constants = keys.get("constants", {})
    if not isinstance(constants, Mapping):
        raise ConfigError(f"{where}.constants: a table like {{ CW0 = [1, \"H'0802'\"] }}")
    for start, values in constants.items():
        at = f"{where}.constants.{start}"
        first = _table_address(start, at, ("CW",))[1]
        items = values if isinstance(values, list) else [values]
        if first + len(items) > len(plc.cw):
            raise ConfigError(f"{at}: {len(items)} words past CW{len(plc.cw) - 1}")
        for k, value in enumerate(items):
            plc.cw[first + k] = plant_word(value, f"{at}[{k}]")
    blocks = keys.get("text_blocks", {})
    if not isinstance(blocks, Mapping):
        raise ConfigError(f'{where}.text_blocks: a table like {{ TXT0 = {{ indirect = "W20" }} }}')
    for txt, decl in blocks.items():
        plc.declare_text_block(*_declaration(txt, decl, f"{where}.text_blocks.{txt}"))
    if "date" in keys:
        date = _date(keys["date"], f"{where}.date")
        try:
            plc.set_calendar(*date)
        except ConfigError as exc:
            raise ConfigError(f"{where}.date: {exc}") from None
    if "watch" in keys:
        watch = keys["watch"]
        if not isinstance(watch, list) or not all(isinstance(w, str) for w in watch):
            raise ConfigError(f'{where}.watch: a list of objects, e.g. ["W0", "W1210"]')
        for name in watch:
            try:
                plc.read(name)
            except ConfigError as exc:
                raise ConfigError(f"{where}.watch: {exc}") from None
        plc.watch = [str(w).upper() for w in watch]
    program = keys.get("program")
    if program is None:
        return
    if not isinstance(program, str) or not program:
        raise ConfigError(f'{where}.program: {program!r} is not a file name (e.g. "tank.pl7")')
    path = plant_file.base_dir / program
    embedded = resources.files("fieldtwin").joinpath("plants", Path(program).name)
    try:
        if plant_file.name != DEFAULT_NAME and path.exists():
            # a regular file of at most 1 MiB of UTF-8: never a FIFO or /dev/zero
            text = read_text(path, MAX_PROGRAM_BYTES, "PL7 program")
        elif program.endswith(".pl7") and embedded.is_file():  # fieldtwin's own programs
            text, path = embedded.read_text("utf-8"), Path(program)
        else:
            text = read_text(path, MAX_PROGRAM_BYTES, "PL7 program")
    except ConfigError as exc:
        raise ConfigError(f"{where}.program: {exc}") from None
    except ValueError:  # a NUL in the name
        raise ConfigError(f"{where}.program: {program!r} is not a file name") from None
    try:
        plc.load_program(text, source=str(path))
    except ConfigError as exc:
        raise ConfigError(f"{where}.program: {exc}") from None


_DATE_RE = re.compile(r"^(\d{4})-(\d{2})-(\d{2})[T ](\d{2}):(\d{2}):(\d{2})$")


def _date(value: object, where: str) -> tuple[int, int, int, int, int, int]:
    """``date = "1994-07-15T18:05:33"``: the PLC calendar (SW51..SW56) at the start."""
    match = _DATE_RE.match(value) if isinstance(value, str) else None
    if match is None:
        raise ConfigError(f'{where}: {value!r} is not a date (e.g. "1994-07-15T18:05:33")')
    y, mo, d, h, mi, s = (int(g) for g in match.groups())
    return y, mo, d, h, mi, s


def _table_address(text: object, where: str, kinds: tuple[str, ...]) -> tuple[str, int]:
    match = _TABLE_RE.match(text) if isinstance(text, str) else None
    if match is None or match.group(1).upper() not in kinds:
        allowed = " or ".join(f"{k}i" for k in kinds)
        raise ConfigError(f"{where}: {text!r} is not a word address (allowed: {allowed})")
    return match.group(1).upper(), int(match.group(2))


def _declaration(txt: str, decl: object, where: str) -> tuple[int, TxtDeclaration]:
    match = re.match(r"^TXT(\d{1,2})$", txt, re.IGNORECASE)
    if match is None:
        raise ConfigError(f"{where}: {txt!r} is not a Text Block (allowed TXT0..TXT63)")
    if not isinstance(decl, Mapping) or not set(decl) <= {"indirect", "send", "recv", "words"}:
        raise ConfigError(f'{where}: a table of indirect = "Wi", or send = and recv = "Wi"')
    indirect = send = recv = None
    if "indirect" in decl:
        indirect = _table_address(decl["indirect"], f"{where}.indirect", ("W",))[1]
    if "send" in decl:
        send = _table_address(decl["send"], f"{where}.send", ("W", "CW"))
    if "recv" in decl:
        recv = _table_address(decl["recv"], f"{where}.recv", ("W",))
    words = decl.get("words")
    if words is not None and (
        isinstance(words, bool) or not isinstance(words, int) or not 1 <= words <= 127
    ):
        raise ConfigError(
            f"{where}.words: {words!r} not allowed (the table's length, 1..127 words)"
        )
    return int(match.group(1)), TxtDeclaration(indirect, send, recv, words)


def _initial_outputs(plc: Plc, outputs: object, where: str) -> None:
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
