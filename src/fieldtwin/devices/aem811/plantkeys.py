"""The AEM 811 keys of a plant file's ``[[module]]`` table (docs/aem811.md).

``config`` (or ``config_words``) and ``threshold0``/``threshold1`` are applied
once, at the end of the first initial self-test, as if the PLC program had sent
them by Text Block while the module was stopped (requests H'40', 2 and 4): a
power break later loses them, as on the real module (AEM 2.5-3).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fieldtwin.devices.aem811.faults import FAULTS, NAMES
from fieldtwin.errors import ConfigError
from fieldtwin.signals.spec import analog_from_spec
from fieldtwin.tsx.aem811.config import DEFAULT_CONFIG, PERIOD_ID, Rejection, parse_configuration
from fieldtwin.tsx.aem811.inputs import ChannelInput
from fieldtwin.tsx.aem811.module import Aem811
from fieldtwin.tsx.aem811.ranges import RANGES, range_by_name
from fieldtwin.tsx.aem811.requests import write_configuration
from fieldtwin.tsx.aem811.scaling import ChannelConfig, Scaling
from fieldtwin.words import parse_word, words_to_bytes

CHANNEL_KEYS = ("channel", "mode", "range", "scaling", "sqrt", "continuity", "high", "low")
KEYS = ("quantize", "inputs", "faults", "config", "config_words", "threshold0", "threshold1")
_SCALINGS = {
    "input": Scaling.INPUT_RANGE, "input_range": Scaling.INPUT_RANGE, "a": Scaling.INPUT_RANGE,
    "standard": Scaling.STANDARD, "b": Scaling.STANDARD,
    "user": Scaling.USER, "c": Scaling.USER,
}  # fmt: skip


@dataclass(frozen=True, slots=True)
class Startup:
    """What the plant file sends the module after its first self-test."""

    config: bytes | None
    thresholds: tuple[tuple[int, ...] | None, ...]

    def apply(self, mod: Aem811) -> None:
        if self.config is not None:
            write_configuration(mod, self.config)
        for level, values in enumerate(self.thresholds):
            if values is not None:
                mod.thresholds.write(level, values)


def read_plant_table(mod: Aem811, table: Mapping[str, Any], where: str, base_dir: Path) -> None:
    unknown = sorted(set(table) - set(KEYS))
    if unknown:
        raise ConfigError(f"{where}.{unknown[0]}: unknown key (allowed: {', '.join(KEYS)})")
    if "quantize" in table:
        if not isinstance(table["quantize"], bool):
            raise ConfigError(f"{where}.quantize: {table['quantize']!r} is not true or false")
        mod.quantize = table["quantize"]
    for index, item in enumerate(_list(table, "inputs", where)):
        _input(mod, item, f"{where}.inputs[{index}]", base_dir)
    for index, name in enumerate(_list(table, "faults", where)):
        if name not in NAMES:
            allowed = ", ".join(NAMES)
            raise ConfigError(f"{where}.faults[{index}]: {name!r} (allowed: {allowed})")
        FAULTS.inject(mod, name, True, {})
    startup = Startup(_config(table, where), tuple(_thresholds(table, where, lv) for lv in (0, 1)))
    if startup.config is not None or any(t is not None for t in startup.thresholds):
        mod.schedule_startup(startup)


def _list(table: Mapping[str, Any], key: str, where: str) -> list[Any]:
    value = table.get(key, [])
    if not isinstance(value, list):
        raise ConfigError(f"{where}.{key}: {value!r} is not a list")
    return value


def _input(mod: Aem811, item: Any, where: str, base_dir: Path) -> None:
    if not isinstance(item, Mapping):
        raise ConfigError(f"{where}: not a table (e.g. {{ channel = 0, volts = 5.0 }})")
    channel = item.get("channel")
    if isinstance(channel, bool) or not isinstance(channel, int) or not 0 <= channel <= 7:
        raise ConfigError(f"{where}.channel: {channel!r} (allowed 0..7)")
    kinds = [k for k in ("volts", "milliamps", "open_circuit") if k in item]
    extra = sorted(set(item) - {"channel", "volts", "milliamps", "open_circuit"})
    if extra or len(kinds) != 1:
        bad = extra[0] if extra else "volts"
        raise ConfigError(f"{where}.{bad}: give exactly one of volts, milliamps, open_circuit")
    key = kinds[0]
    if key == "open_circuit":
        if item[key] is not True:
            raise ConfigError(f"{where}.open_circuit: only true is allowed")
        mod.inputs[channel] = ChannelInput(open=True)
        return
    signal = analog_from_spec(item[key], where=f"{where}.{key}", base_dir=base_dir)
    mod.inputs[channel] = ChannelInput("V" if key == "volts" else "mA", 0.0, signal)


def _config(table: Mapping[str, Any], where: str) -> bytes | None:
    if "config" in table and "config_words" in table:
        raise ConfigError(f"{where}.config_words: give either config or config_words")
    if "config_words" in table:
        raw = table["config_words"]
        if not isinstance(raw, list):
            raise ConfigError(f"{where}.config_words: {raw!r} is not a list of words")
        listed = [_word(w, f"{where}.config_words[{i}]") for i, w in enumerate(raw)]
        return _checked(listed, f"{where}.config_words")
    if "config" not in table:
        return None
    spec = table["config"]
    if not isinstance(spec, Mapping):
        raise ConfigError(f"{where}.config: not a table (e.g. {{ period = 30, channels = [] }})")
    _known(spec, ("period", "channels"), f"{where}.config")
    words: list[int] = []
    if "period" in spec:
        words += [PERIOD_ID, _int(spec["period"], f"{where}.config.period")]
    channels = spec.get("channels", [])
    if not isinstance(channels, list):
        raise ConfigError(f"{where}.config.channels: not a list of tables")
    for index, ch in enumerate(channels):
        words += _channel_words(ch, f"{where}.config.channels[{index}]")
    return _checked(words, f"{where}.config")


def _channel_words(ch: Any, where: str) -> list[int]:
    if not isinstance(ch, Mapping):
        raise ConfigError(f'{where}: not a table (e.g. {{ channel = 0, range = "4/20mA" }})')
    _known(ch, CHANNEL_KEYS, where)
    channel = _int(ch.get("channel"), f"{where}.channel")
    if not 0 <= channel <= 7:
        raise ConfigError(f"{where}.channel: {channel} (allowed 0..7)")
    for key in ("sqrt", "continuity"):
        if key in ch and not isinstance(ch[key], bool):
            raise ConfigError(f"{where}.{key}: {ch[key]!r} is not true or false")
    if "mode" in ch:
        clash = sorted(set(ch) & {"range", "scaling", "sqrt", "continuity"})
        if clash:
            raise ConfigError(f"{where}.{clash[0]}: give either mode or range/scaling/sqrt")
        mode = _word(ch["mode"], f"{where}.mode")
    else:
        rng = ch.get("range", 0)
        found = RANGES[rng] if isinstance(rng, int) and 0 <= rng <= 8 else None
        found = found or (range_by_name(rng) if isinstance(rng, str) else None)
        if found is None:
            names = ", ".join(r.name.replace(" ", "") for r in RANGES)
            raise ConfigError(f"{where}.range: {rng!r} (allowed 0..8 or {names})")
        scaling = _SCALINGS.get(str(ch.get("scaling", "input")).lower())
        if scaling is None:
            raise ConfigError(
                f"{where}.scaling: {ch.get('scaling')!r} (allowed input, standard, user)"
            )
        cfg = ChannelConfig(found.number, bool(ch.get("sqrt")), scaling, bool(ch.get("continuity")))
        mode = cfg.mode_word
    words = [0x00C0 | channel, mode]
    if (mode >> 4) & 0xF == Scaling.USER:
        words += [_int(ch.get(k), f"{where}.{k}") & 0xFFFF for k in ("high", "low")]
    elif "high" in ch or "low" in ch:  # AEM 3.4-3: limits only with User range scaling
        key = "high" if "high" in ch else "low"
        raise ConfigError(f"{where}.{key}: limits are only for user scaling (scaling = user)")
    return words


def _known(table: Mapping[str, Any], allowed: tuple[str, ...], where: str) -> None:
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ConfigError(f"{where}.{unknown[0]}: unknown key (allowed: {', '.join(allowed)})")


def _checked(words: list[int], where: str) -> bytes:
    data = words_to_bytes(words)
    result = parse_configuration(data, DEFAULT_CONFIG)
    if isinstance(result, Rejection):
        raise ConfigError(f"{where}: the module would refuse it: {result.reason}")
    return data


def _thresholds(table: Mapping[str, Any], where: str, level: int) -> tuple[int, ...] | None:
    key = f"threshold{level}"
    if key not in table:
        return None
    values = table[key]
    if not isinstance(values, list) or len(values) != 8:
        raise ConfigError(f"{where}.{key}: {values!r} (allowed a list of 8 integers)")
    out = tuple(_int(v, f"{where}.{key}") for v in values)
    if any(not -32768 <= v <= 32767 for v in out):
        raise ConfigError(f"{where}.{key}: values must be within -32768..32767")
    return out


def _int(value: Any, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(f"{where}: {value!r} is not an integer")
    return value


def _word(value: Any, where: str) -> int:
    if isinstance(value, str):
        try:
            return parse_word(value)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None
    number = _int(value, where)
    if not -32768 <= number <= 65535:
        raise ConfigError(f"{where}: {number} does not fit a word (allowed -32768..65535)")
    return number & 0xFFFF
