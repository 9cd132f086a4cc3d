"""``[[tes]]`` tables of a plant file -> TES cores (their endpoints: fieldtwin.facade.tes).

    [[tes]]
    model = "TES 8EA"                      # fixed keys: model, slave, endpoint
    slave = 3                              # on the port `link` names (absent: the EEPROM's)
    endpoint = "rtu+tcp://127.0.0.1:5021"  # several TES naming one RTU endpoint share a line
    name = "boiler"                        # the EEPROM's name in the store (optional)
    store = "eeprom.db"                    # SQLite parameter store (default: in memory)
    prm_jumper = false                     # true: factory settings, slave 1 (§3.1.2)
    link = "rs485"                         # which TES port the endpoint is (rs485, rs232)
    wire_timing = true                     # RTU on pty/serial/rtu+tcp: replies at line speed
    strict_line = true                     # pty: a master at another speed gets no answer
    inputs = { 0 = true, a2 = 4.5, a3 = { kind = "square", low = 1.0, high = 9.0, period_s = 2 } }
    faults = { short = [3], open = [7], not_ready_ms = 2, powered = true }

Errors name the file and the field path: ``plant.toml: tes[1].slave: ...``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from fieldtwin.clock import MS, SimClock
from fieldtwin.endpoint import Endpoint, parse_endpoint
from fieldtwin.errors import ConfigError, refuse_unknown_keys
from fieldtwin.modbus.model import Link
from fieldtwin.signals import analog_from_spec, discrete_from_spec
from fieldtwin.tes.model import Tes
from fieldtwin.tes.models import model_named
from fieldtwin.tes.port import check_fixed_format

KEYS = (
    "model",
    "slave",
    "endpoint",
    "name",
    "store",
    "prm_jumper",
    "link",
    "wire_timing",
    "strict_line",
    "inputs",
    "faults",
)
FAULT_KEYS = ("short", "open", "not_ready_ms", "powered")
LINKS = {"rs485": Link.RS485, "rs232": Link.RS232}


def build_tes(
    tables: Sequence[Mapping[str, Any]], clock: SimClock, where: str, base_dir: Path
) -> list[Tes]:
    """Validate every ``[[tes]]`` table and build its TES on ``clock``."""
    built = [
        build_one(table, clock, f"{where}: tes[{i}]", base_dir) for i, table in enumerate(tables)
    ]
    check_lines(built, tables, where)
    return built


def build_one(
    table: Mapping[str, Any], clock: SimClock, at: str, base_dir: Path, *, signals: bool = True
) -> Tes:
    """One ``[[tes]]`` table; ``signals=False`` leaves ``inputs`` to the caller (the plant
    builder sets them through the Device face, fieldtwin.devices.tes)."""
    if not isinstance(table, Mapping):
        raise ConfigError(f"{at}: not a table (allowed keys: {', '.join(KEYS)})")
    refuse_unknown_keys(table, KEYS, at)
    model = _model(table, at)
    # the number on the port `link` names; absent: the EEPROM's (factory 1, §3.1.2)
    slave = None if "slave" not in table else _slave(table["slave"], f"{at}.slave")
    endpoint_of(table, at)
    link = link_of(table, at)
    store = table.get("store")
    if store is not None and not isinstance(store, str):
        raise ConfigError(f"{at}.store: {store!r} is not a file path")
    prm = table.get("prm_jumper", False)
    if not isinstance(prm, bool):
        raise ConfigError(f"{at}.prm_jumper: {prm!r} not allowed (allowed: true, false)")
    name = table.get("name")
    if name is not None and not isinstance(name, str):
        raise ConfigError(f"{at}.name: {name!r} is not a string")
    wire = wire_timing_of(table, at)
    path = None if store is None else base_dir / store
    try:
        tes = Tes(model, slave, clock=clock, store=path, prm_jumper=prm, name=name, link=link)
    except ConfigError as exc:
        raise ConfigError(f"{at}: {exc}") from None
    tes.wire_timing = wire
    tes.strict_line = strict_line_of(table, at)
    if signals:
        _inputs(tes, table.get("inputs", {}), f"{at}.inputs", base_dir)
    faults = table.get("faults", {})
    if not isinstance(faults, list):  # a list of fault names: the Device face's
        _faults(tes, faults, f"{at}.faults")
    return tes


def _model(table: Mapping[str, Any], at: str) -> str:
    if "model" not in table:
        raise ConfigError(f"{at}.model: missing (allowed: TES 16EST, TES 8EA, ...)")
    try:
        return model_named(str(table["model"])).name
    except ConfigError as exc:
        raise ConfigError(f"{at}.model: {exc}") from None


def _slave(value: object, at: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 247:
        raise ConfigError(f"{at}: {value!r} out of range (allowed 1..247)")
    return value


def endpoint_of(table: Mapping[str, Any], at: str) -> Endpoint:
    url = table.get("endpoint")
    if not isinstance(url, str):
        raise ConfigError(f"{at}.endpoint: missing or not a string (e.g. tcp://127.0.0.1:5020)")
    try:
        endpoint = parse_endpoint(url)
    except ConfigError as exc:
        raise ConfigError(f"{at}.endpoint: {exc}") from None
    if endpoint.scheme == "memory":
        raise ConfigError(
            f"{at}.endpoint: 'memory' is for tests (allowed: tcp, rtu+tcp, pty, serial)"
        )
    try:  # §3.1.3 8 data bits and 1 stop bit are fixed
        check_fixed_format(endpoint.settings)
    except ConfigError as exc:
        raise ConfigError(f"{at}.endpoint: {exc}") from None
    return endpoint


def link_of(table: Mapping[str, Any], at: str) -> Link:
    name = table.get("link", "rs485")
    if not isinstance(name, str) or name not in LINKS:
        raise ConfigError(f"{at}.link: {name!r} not allowed (allowed: rs485, rs232)")
    return LINKS[name]


def _inputs(tes: Tes, inputs: object, at: str, base_dir: Path) -> None:
    if not isinstance(inputs, Mapping):
        raise ConfigError(f"{at}: not a table (e.g. {{ 0 = true, a2 = 4.5 }})")
    for key, spec in inputs.items():
        field = f"{at}.{key}"
        text = str(key).strip().lower()
        analog = text.startswith("a")
        number = text[1:] if analog else text
        if not number.isdigit():
            raise ConfigError(f"{field}: not an input (allowed 0..31 digital, a0..a7 analog)")
        try:
            if analog:
                tes.set_signal(
                    int(number), analog_from_spec(spec, where=field, base_dir=base_dir), False
                )
            else:
                tes.set_signal(
                    int(number), discrete_from_spec(spec, where=field, base_dir=base_dir), True
                )
        except ConfigError as exc:
            raise ConfigError(
                exc.args[0] if str(exc).startswith(field) else f"{field}: {exc}"
            ) from None


def _faults(tes: Tes, faults: object, at: str) -> None:
    if not isinstance(faults, Mapping):
        raise ConfigError(f"{at}: not a table (allowed keys: {', '.join(FAULT_KEYS)})")
    refuse_unknown_keys(faults, FAULT_KEYS, at)
    for wiring in ("short", "open"):
        for i in _int_list(faults.get(wiring, []), f"{at}.{wiring}"):
            try:
                tes.set_wiring(i, wiring)
            except ConfigError as exc:
                raise ConfigError(f"{at}.{wiring}: {exc}") from None
    window = faults.get("not_ready_ms", 0)
    if isinstance(window, bool) or not isinstance(window, int | float) or not 0 <= window < 100:
        raise ConfigError(f"{at}.not_ready_ms: {window!r} not allowed (allowed 0..<100 ms)")
    tes.not_ready_window_us = round(window * MS)
    powered = faults.get("powered", True)
    if not isinstance(powered, bool):
        raise ConfigError(f"{at}.powered: {powered!r} not allowed (allowed: true, false)")
    if not powered:
        tes.power_off()


def _int_list(value: object, at: str) -> list[int]:
    if not isinstance(value, list) or not all(
        isinstance(v, int) and not isinstance(v, bool) for v in value
    ):
        raise ConfigError(f"{at}: {value!r} is not a list of input numbers")
    return list(value)


def wire_timing_of(table: Mapping[str, Any], at: str) -> bool:
    """``wire_timing``: true (the default) or false."""
    wire = table.get("wire_timing", True)
    if not isinstance(wire, bool):
        raise ConfigError(f"{at}.wire_timing: {wire!r} not allowed (allowed: true, false)")
    return wire


def strict_line_of(table: Mapping[str, Any], at: str) -> bool:
    """``strict_line``: true (the default: a pty master's settings must match) or false."""
    strict = table.get("strict_line", True)
    if not isinstance(strict, bool):
        raise ConfigError(f"{at}.strict_line: {strict!r} not allowed (allowed: true, false)")
    return strict


def check_lines(built: list[Tes], tables: Sequence[Mapping[str, Any]], where: str) -> None:
    """Two TES answering the same number on one line would both reply."""
    seen: dict[tuple[str, int], int] = {}
    ports: dict[str, int] = {}
    for i, (tes, table) in enumerate(zip(built, tables, strict=True)):
        url, link = str(endpoint_of(table, f"{where}: tes[{i}]")), link_of(table, "")
        first = ports.setdefault(url, i)
        if link is not link_of(tables[first], ""):  # one endpoint is one line: one port
            raise ConfigError(
                f"{where}: tes[{i}].link: {link.value} on {url}, where tes[{first}] is on"
                f" {link_of(tables[first], '').value} (one endpoint is one line)"
            )
        wire, first_wire = wire_timing_of(table, ""), wire_timing_of(tables[first], "")
        if wire is not first_wire:  # one line has one timing
            raise ConfigError(
                f"{where}: tes[{i}].wire_timing: {str(wire).lower()} on {url}, where"
                f" tes[{first}] has {str(first_wire).lower()} (one endpoint is one line)"
            )
        key = (url, tes.slave_for(link))
        if key in seen:
            raise ConfigError(
                f"{where}: tes[{i}].slave: {key[1]} already answers on {key[0]} (tes[{seen[key]}])"
            )
        seen[key] = i
