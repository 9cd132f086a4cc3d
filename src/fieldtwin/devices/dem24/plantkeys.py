"""The ``[[module]]`` keys of a DEM 2412 / 2413 in a plant file, and console values.

```toml
[[module]]
type = "TSX DEM 2412"
rack = 0
slot = 4
inputs = { "0" = true, "1" = 24.0, "2" = { kind = "pulse", period_s = 2.0 } }
sync = { period_s = 30 }            # or { period_s = 60, start_s = 0.5 }, or { from_slot = 3 }
time = "1994-07-15T18:05:33"        # sent as a request 2 after the first self-test
time_indicator = 1
config = ["H'0014'", 10, 5, 3, 5, 2, 60, 500, 60]   # a request H'40' after the first self-test
clock_drift_ppm = 10.0
faults = ["terminal_block"]
```
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from fieldtwin.clock import seconds
from fieldtwin.devices.dem24.faults import FAULTS
from fieldtwin.errors import ConfigError
from fieldtwin.signals import signal_from_spec
from fieldtwin.tsx.dem24.civil import parse_iso
from fieldtwin.tsx.dem24.config import Refusal, check_config
from fieldtwin.tsx.dem24.inputs import CHANNELS
from fieldtwin.tsx.dem24.module import Dem24
from fieldtwin.tsx.dem24.timebase import TimeReference
from fieldtwin.units import VOLTS, parse_bool, parse_quantity
from fieldtwin.words import plant_word

KEYS = ("inputs", "sync", "time", "time_indicator", "config", "clock_drift_ppm", "faults")


def console_value(text: str) -> bool | float:
    """``1``/``0``/``on``/``off``/``true``/``false``, or volts: ``18.5`` / ``18.5V``."""
    try:
        return parse_bool(text)
    except ConfigError:
        pass
    try:
        return parse_quantity(text, (VOLTS,)).value
    except ConfigError:
        raise ConfigError(
            f"input value {text!r} not allowed (allowed 0, 1, on, off, or volts such as 18.5V)"
        ) from None


WireSync = Callable[[int, int], None]  # (from_rack, from_slot): done by the plant builder


def configure(
    mod: Dem24,
    table: Mapping[str, Any],
    where: str,
    base_dir: Path,
    wire_sync: WireSync | None = None,
) -> None:
    """The DEM keys; ``sync = { from_slot }`` needs ``wire_sync`` (the plant finds the partner
    through its PLC once every module is in: fieldtwin.devices.dem24)."""
    unknown = sorted(set(table) - set(KEYS))
    if unknown:
        raise ConfigError(
            f"{where}.{unknown[0]}: unknown key for {mod.type_name} (allowed: {', '.join(KEYS)})"
        )
    if "clock_drift_ppm" in table:
        mod.set_clock_drift(_number(table["clock_drift_ppm"], f"{where}.clock_drift_ppm"))
    _inputs(mod, table.get("inputs", {}), f"{where}.inputs", base_dir)
    if "sync" in table:
        _sync(mod, table["sync"], f"{where}.sync", wire_sync)
    if "config" in table:
        _config(mod, table["config"], f"{where}.config")
    if "time" in table:
        _time(mod, table, where)
    elif "time_indicator" in table:
        raise ConfigError(f"{where}.time_indicator: given without time")
    faults = table.get("faults", [])
    if not isinstance(faults, list):
        raise ConfigError(f"{where}.faults: {faults!r} is not a list of fault names")
    for name in faults:
        FAULTS.inject(mod, str(name), True, {})


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(f"{where}: {value!r} is not a number")
    return float(value)


def _inputs(mod: Dem24, spec: Any, where: str, base_dir: Path) -> None:
    if not isinstance(spec, Mapping):
        raise ConfigError(f"{where}: must be a table of channel = value or signal")
    for key, value in spec.items():
        if not str(key).isdigit() or not 0 <= int(key) < CHANNELS:
            raise ConfigError(f'{where}.{key}: not a channel (allowed "0".."23")')
        channel = int(key)
        if isinstance(value, bool | int | float):
            mod.set_input(channel, value)
            continue
        signal = signal_from_spec(value, where=f"{where}.{key}", base_dir=base_dir)
        mod.set_signal(channel, signal)


def _sync(mod: Dem24, spec: Any, where: str, wire_sync: WireSync | None) -> None:
    if not isinstance(spec, Mapping):
        raise ConfigError(f"{where}: must be a table ({{ period_s = 30 }} or {{ from_slot = 4 }})")
    rest = dict(spec)
    if "from_slot" in rest:
        slot = rest.pop("from_slot")
        rack = rest.pop("from_rack", 0)
        if rest or not all(isinstance(v, int) and not isinstance(v, bool) for v in (rack, slot)):
            raise ConfigError(f"{where}: from_rack and from_slot take integers, nothing else")
        if wire_sync is None:
            raise ConfigError(f"{where}.from_slot: only a plant file wires a sync output")
        wire_sync(rack, slot)
        return
    period = _number(rest.pop("period_s", None), f"{where}.period_s")
    start = _number(rest.pop("start_s", 0.0), f"{where}.start_s")
    if rest:
        raise ConfigError(f"{where}.{sorted(rest)[0]}: unknown (allowed period_s, start_s)")
    if period <= 0 or start < 0:
        raise ConfigError(f"{where}: period_s must be > 0 and start_s >= 0")
    mod.attach_pulse_source(seconds(period), seconds(start))


def _config(mod: Dem24, spec: Any, where: str) -> None:
    if not isinstance(spec, list) or len(spec) != 9:
        raise ConfigError(f"{where}: must be a list of the 9 configuration words (DEM 3.2-1)")
    words = [plant_word(w, f"{where}[{i}]") for i, w in enumerate(spec)]
    result = check_config(words)
    if isinstance(result, Refusal):
        raise ConfigError(f"{where}: refused by the module: {result.reason}")
    mod.plant_startup.append(_once(lambda m, now: m.apply_config(result, now)))


def _time(mod: Dem24, table: Mapping[str, Any], where: str) -> None:
    text = table["time"]
    if not isinstance(text, str):
        raise ConfigError(f'{where}.time: {text!r} is not a string like "1994-07-15T18:05:33"')
    civil = parse_iso(text, f"{where}.time")
    indicator = table.get("time_indicator", 1)
    if isinstance(indicator, bool) or not isinstance(indicator, int) or not 0 <= indicator <= 255:
        raise ConfigError(f"{where}.time_indicator: {indicator!r} not allowed (allowed 0..255)")
    ref = TimeReference(civil, indicator)

    def reference(m: Dem24, now: int) -> None:
        m.timebase.reference(ref, now)

    mod.plant_startup.append(_once(reference))


Startup = Callable[["Dem24", int], None]


def _once(action: Startup) -> Startup:
    """docs/plant.md: a plant file's configuration is sent at the end of the first initial
    self-test only; a power break or a reinsertion loses it, as on the module (DEM 2.5-3)."""
    sent: list[bool] = []

    def send(mod: Dem24, now: int) -> None:
        if not sent:
            sent.append(True)
            action(mod, now)

    return send
