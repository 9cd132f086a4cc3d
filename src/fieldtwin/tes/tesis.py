"""``fieldtwin tesis``: the TESIS32 workbench (§3, §5) over a TES parameter store.

    fieldtwin tesis --store plant.db --model "TES 8EA" show
    fieldtwin tesis --store plant.db set ai0.filter 16 ai0.scale on
    fieldtwin tesis --store plant.db validate
    fieldtwin tesis --store plant.db export eeprom.toml
    fieldtwin tesis --store plant.db import eeprom.json
    fieldtwin tesis --store plant.db iotest --input 0=1 --input a2=4.5 --output 1=1

Parameters are checked before anything is written; a write is one
transaction.  ``iotest`` powers a simulated TES on the stored EEPROM, applies
inputs, forces outputs and shows every input and output (§5).
"""

from __future__ import annotations

import argparse
import json
import tomllib
from pathlib import Path

from rich.console import Console
from rich.table import Table

from fieldtwin.errors import ConfigError
from fieldtwin.tes.eeprom import problems
from fieldtwin.tes.memmap import memory_map
from fieldtwin.tes.model import Tes
from fieldtwin.tes.models import MODELS, TesModel, model_named
from fieldtwin.tes.params import Value, complete, factory, param_specs
from fieldtwin.tes.store import ParameterStore
from fieldtwin.tes.tesis_io import apply_forces, io_tables


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="fieldtwin tesis",
        description="TESIS32 workbench for TES",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n"
        "  fieldtwin tesis models\n"
        '  fieldtwin tesis --store eeprom.db --model "TES 8EA" factory\n'
        "  fieldtwin tesis --store eeprom.db set ai0.filter 16 && fieldtwin tesis --store"
        " eeprom.db show",
    )
    p.add_argument("--store", help="SQLite parameter store (default: in memory)")
    p.add_argument("--device", help="TES name in the store (default: the only one)")
    p.add_argument("--model", help=f"TES model ({', '.join(MODELS)})")
    p.add_argument("--prm", action="store_true", help="Prm jumper fitted: factory settings")
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("models", help="list the TES models")
    show = sub.add_parser("show", help="show every parameter")
    show.add_argument("--json", action="store_true")
    setp = sub.add_parser("set", help="set NAME VALUE [NAME VALUE ...] (validated)")
    setp.add_argument("pairs", nargs="+", metavar="NAME VALUE")
    sub.add_parser("validate", help="check every parameter of the TES")
    sub.add_parser("factory", help="write the factory settings (§3.1.2)")
    sub.add_parser("map", help="print the model's memory map (§6)")
    exp = sub.add_parser("export", help="write the EEPROM to FILE (.json or .toml)")
    exp.add_argument("file")
    imp = sub.add_parser("import", help="load the EEPROM from FILE (.json or .toml)")
    imp.add_argument("file")
    io = sub.add_parser("iotest", help="show all inputs and outputs, force outputs (§5)")
    io.add_argument("--input", action="append", default=[], metavar="I=V", help="0=1, a2=4.5")
    io.add_argument("--output", action="append", default=[], metavar="I=V", help="3=1, a4=16384")
    io.add_argument("--advance", type=float, default=0.1, help="simulated seconds (default 0.1)")
    return p


# commands that change nothing in the store: they never create a file nor a device
READ_ONLY = frozenset({"show", "validate", "map", "export", "iotest"})


class _Console(Console):
    def on_broken_pipe(self) -> None:
        """The reader went away: `fieldtwin`'s main exits quietly (rich would exit 1)."""
        raise BrokenPipeError


def main(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    console = _Console(highlight=False, width=120)
    try:
        if args.command == "models":
            _models(console)
            return 0
        if args.command == "map" and args.model is not None:
            _print_map(model_named(args.model), console)  # the map needs no store
            return 0
        tes = _open(args, writable=args.command not in READ_ONLY)
        return _COMMANDS[args.command](tes, args, console)
    except ConfigError as exc:
        Console(stderr=True, highlight=False, soft_wrap=True).print(f"tesis: {exc}", markup=False)
        return 2


_WRITERS_HINT = "`set`, `factory` or `import` with --model MODEL writes one"


def _open(args: argparse.Namespace, writable: bool) -> Tes:
    store = ParameterStore(args.store, readonly=not writable)
    devices = store.devices()
    device = args.device
    if device is None and len(devices) == 1:
        device = next(iter(devices))
    elif device is None and len(devices) > 1:
        raise ConfigError(
            f"{store.where} holds several TES: give --device"
            f" (devices stored: {store.describe_devices()})"
        )
    elif device is not None and device not in devices and (store.readonly or not args.model):
        # only a writing command with a model may add a device
        raise ConfigError(f"{store.no_device(device)}; {_WRITERS_HINT}")
    model = args.model or (devices.get(device) if device else None)
    if model is None:
        raise ConfigError(
            f"{store.where} holds no TES: give --model (and --device NAME; {_WRITERS_HINT})"
        )
    if store.readonly and (device or "") not in devices:
        name = device or f"{model_named(model).name} #1"
        raise ConfigError(
            f"TES parameter store {store.where} holds no TES {name!r} (devices stored:"
            f" {store.describe_devices()}); a read-only command stores none: {_WRITERS_HINT}"
        )
    try:
        found = model_named(model)
    except ConfigError as exc:
        raise ConfigError(f"{store.where}: device {device!r}: {exc}") from None
    stored = devices.get(device or "")
    if args.device is None and stored is not None and stored != found.name:
        raise ConfigError(
            f"{store.where} holds {device!r}, a {stored}, not a {found.name}:"
            f" give --device NAME for another TES"
        )
    return Tes(found, store=store, name=device, prm_jumper=args.prm)


def _models(console: Console) -> None:
    table = Table("model", "map", "digital in", "digital out", "analog in", "analog out")
    for m in MODELS.values():
        ai = ",".join(map(str, m.analog_inputs)) or "-"
        ao = ",".join(map(str, m.analog_outputs)) or "-"
        table.add_row(
            m.name, f"§{m.family.value}", str(m.digital_inputs), str(m.digital_outputs), ai, ao
        )
    console.print(table)


def _show(tes: Tes, args: argparse.Namespace, console: Console) -> int:
    values = tes.eeprom()
    if args.json:
        console.print_json(json.dumps(values))
        return 0
    table = Table(
        "parameter", "value", "allowed", "unit", "meaning", title=f"{tes.name} ({tes.model.name})"
    )
    for name, spec in param_specs(tes.model).items():
        table.add_row(name, str(values[name]), spec.allowed(), spec.unit, spec.help)
    console.print(table)
    return 0


def _set(tes: Tes, args: argparse.Namespace, console: Console) -> int:
    pairs = args.pairs
    if len(pairs) % 2:
        raise ConfigError(f"set: {pairs[-1]!r} has no value (give NAME VALUE pairs)")
    changes: dict[str, Value] = dict(zip(pairs[::2], pairs[1::2], strict=True))
    tes.write_eeprom(changes)
    for name in changes:
        console.print(f"{name} = {tes.eeprom()[name]}", markup=False)
    return 0


def _validate(tes: Tes, args: argparse.Namespace, console: Console) -> int:
    found = problems(tes.model, complete(tes.model, tes.store.load(tes.name)))
    for problem in found:
        console.print(f"invalid: {problem}", markup=False)
    if not found:
        console.print(f"{tes.name}: {len(param_specs(tes.model))} parameters valid", markup=False)
    return 1 if found else 0


def _factory(tes: Tes, args: argparse.Namespace, console: Console) -> int:
    tes.store.save(tes.name, tes.model.name, factory(tes.model))
    console.print(f"{tes.name}: factory settings written", markup=False)
    return 0


def _map(tes: Tes, args: argparse.Namespace, console: Console) -> int:
    _print_map(tes.model, console)
    return 0


def _print_map(model: TesModel, console: Console) -> None:
    table = Table("hex", "dec", "access", "name", "meaning", title=f"{model.name} memory map")
    for reg in memory_map(model):
        table.add_row(
            f"{reg.address:03X}h", str(reg.address), reg.access.value, reg.name, reg.meaning
        )
    console.print(table)


def _export(tes: Tes, args: argparse.Namespace, console: Console) -> int:
    path = Path(args.file)
    doc: dict[str, object] = {"model": tes.model.name, "device": tes.name}
    doc["parameters"] = tes.eeprom()
    if path.suffix == ".toml":
        text = _toml(doc)
    elif path.suffix == ".json":
        text = json.dumps(doc, indent=2) + "\n"
    else:
        raise ConfigError(f"export: {path}: unknown format (allowed .json, .toml)")
    path.write_text(text, encoding="utf-8")
    console.print(f"{tes.name}: EEPROM written to {path}", markup=False)
    return 0


def _toml(doc: dict[str, object]) -> str:
    lines = [f"model = {json.dumps(doc['model'])}", f"device = {json.dumps(doc['device'])}", ""]
    lines.append("[parameters]")
    params = doc["parameters"]
    assert isinstance(params, dict)
    lines += [f"{json.dumps(name)} = {json.dumps(value)}" for name, value in params.items()]
    return "\n".join(lines) + "\n"


def _import(tes: Tes, args: argparse.Namespace, console: Console) -> int:
    path = Path(args.file)
    try:
        text = path.read_text(encoding="utf-8")
        doc = tomllib.loads(text) if path.suffix == ".toml" else json.loads(text)
    except (OSError, ValueError) as exc:
        raise ConfigError(f"import: {path}: {exc}") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("parameters"), dict):
        raise ConfigError(f"import: {path}: no [parameters] table")
    try:
        model = model_named(str(doc.get("model", "")))
    except ConfigError as exc:
        raise ConfigError(f"import: {path}: model: {exc}") from None
    if model is not tes.model:
        raise ConfigError(f"import: {path}: holds a {doc.get('model')}, not a {tes.model.name}")
    try:
        tes.write_eeprom(doc["parameters"])
    except ConfigError as exc:
        raise ConfigError(f"import: {path}: {exc}") from None
    console.print(f"{tes.name}: EEPROM loaded from {path}", markup=False)
    return 0


def _iotest(tes: Tes, args: argparse.Namespace, console: Console) -> int:
    for note in apply_forces(tes, args.input, args.output):
        console.print(f"note: {note}", markup=False)
    tes.advance(args.advance)
    for table in io_tables(tes):
        console.print(table)
    return 0


_COMMANDS = {
    "show": _show,
    "set": _set,
    "validate": _validate,
    "factory": _factory,
    "map": _map,
    "export": _export,
    "import": _import,
    "iotest": _iotest,
}
