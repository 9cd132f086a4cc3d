"""Building a plant: a checked description -> the PLC, its modules and the TES.

Every device is built with one build context (clock, PLC, base directory);
wiring between devices (a DEM's sync output) is done once every device is in.
Nothing is opened here: the ports are bound afterwards (fieldtwin.plant.ports,
fieldtwin.session), so a mistake anywhere in the file leaves no port open.
What needs the built PLC (constants, text blocks, the program, the initial
outputs) is checked here, with the same field paths as the reader's errors.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from functools import partial
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from fieldtwin.clock import SimClock
from fieldtwin.devices.context import BuildContext
from fieldtwin.errors import ConfigError
from fieldtwin.plant.reading import (
    DEFAULT_NAME,
    PlantDescription,
    PlantFile,
    PlcDescription,
    describe,
    plant_speed,
)
from fieldtwin.plant.tags import read_tags
from fieldtwin.plant.value import Plant
from fieldtwin.runtime.events import EventBus
from fieldtwin.textfile import read_text
from fieldtwin.tsx.bus import Host
from fieldtwin.tsx.plc import MAX_PROGRAM_BYTES, Plc
from fieldtwin.tsx.plcmemory import TxtDeclaration
from fieldtwin.words import plant_word

if TYPE_CHECKING:
    from fieldtwin.runtime.runner import Runner

FROM_PLANT = "from plant"  # build_plant(speed=FROM_PLANT): take [run] speed
KIND_PLC = "plc"  # the event of the PLC going to its fault state


def build_plant(
    plant_file: PlantFile | PlantDescription,
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
    source = plant_file if isinstance(plant_file, PlantFile) else plant_file.source
    clock = clock or (runner.clock if runner is not None else SimClock())
    pace = plant_speed(source) if speed == FROM_PLANT else speed
    assert not isinstance(pace, str)
    description = plant_file if isinstance(plant_file, PlantDescription) else describe(source)
    plc = None
    if description.plc is not None:
        plc = _new_plc(description.plc, clock, runner, pace, host)
    ctx = BuildContext(clock, plc, source.base_dir, source.name)
    for device in description.devices:
        ctx.devices.append(device.kind.build(device.table, ctx, device.where))
    ctx.finish()
    if plc is not None and description.plc is not None:
        _initial_outputs(plc, description.plc.outputs, f"{source.name}: plc.outputs")
        _program(plc, description.plc.program, source)
    plant = Plant(
        source.name,
        description.title,
        clock,
        plc,
        list(ctx.devices),
        speed=pace,
        notes=list(ctx.notes),
        source=source,
    )
    plant.tags = read_tags(source.data, source.name, plant)  # checked on the built plant
    if plc is not None:  # the watchdog's trip on the event stream (docs/control.md)
        plc.on_fault = partial(_publish_fault, plant.events)
    return plant


def _publish_fault(events: EventBus, now: int, reason: str) -> None:
    events.publish(now, KIND_PLC, "plc", {"mode": "FAULT", "fault": reason})


def _new_plc(
    description: PlcDescription,
    clock: SimClock,
    runner: Runner | None,
    speed: float | None,
    host: Host | None = None,
) -> Plc:
    return Plc(
        model=description.model,
        scan_ms=description.scan_ms,
        clock=clock,
        runner=runner,
        speed=speed,
        watchdog_ms=description.watchdog_ms,
        host=host,
    )


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
