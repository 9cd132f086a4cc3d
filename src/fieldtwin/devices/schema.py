"""The plant schema: one description of the keys of every device kind's table.

A kind declares its keys (:class:`Key`: name and what it takes); the plant
builder checks every table against it before the device is built, so that an
unknown key, a missing identity key or a value of the wrong type gets the same
field-path error for every kind: ``plant.toml: module[1].slot: ...``.  The
readers here are the only place those messages are written.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from fieldtwin.errors import ConfigError

Table = Mapping[str, object]


@dataclass(frozen=True, slots=True)
class Key:
    """One key of a kind's table: its name and what it takes (docs/plant.md)."""

    name: str
    doc: str


@dataclass(frozen=True, slots=True)
class Schema:
    """The keys of one kind's plant table; ``open`` passes unknown keys on (legacy kinds)."""

    identity: tuple[Key, ...]  # read by the plant builder (type, rack, slot / model, slave...)
    keys: tuple[Key, ...] = ()  # read by the kind's adapter
    open: bool = False

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(k.name for k in (*self.identity, *self.keys))

    def check(self, table: object, where: str, kind: str) -> Table:
        """The table itself, once it is a table with only known keys."""
        checked = table_at(table, where, self.names)
        if not self.open:
            unknown_keys(checked, self.names, where, kind)
        return checked


def table_at(value: object, where: str, allowed: Sequence[str] = ()) -> Table:
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        hint = f" (allowed keys: {', '.join(allowed)})" if allowed else ""
        raise ConfigError(f"{where}: not a table{hint}")
    return value


def unknown_keys(table: Table, allowed: Sequence[str], where: str, kind: str) -> None:
    """``plant.toml: module[0]: unknown key(s) colour (module[0].colour is not a key of
    TSX AEM 811; allowed: ...)``: the table, the keys, the first key's own path."""
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        path = where.rpartition(": ")[2]
        raise ConfigError(
            f"{where}: unknown key(s) {', '.join(unknown)} ({path}.{unknown[0]} is not a key"
            f" of {kind}; allowed: {', '.join(allowed)})"
        )


def integer(table: Table, key: str, where: str, default: int | None = None) -> int:
    value = table.get(key, default)
    if value is None:
        raise ConfigError(f"{where}.{key}: missing (an integer is required)")
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(f"{where}.{key}: {value!r} is not an integer")
    return value


def optional_integer(table: Table, key: str, where: str) -> int | None:
    return None if table.get(key) is None else integer(table, key, where)


def string(table: Table, key: str, where: str, example: str) -> str:
    value = table.get(key)
    if not isinstance(value, str):
        raise ConfigError(f"{where}.{key}: missing or not a string (e.g. {example})")
    return value


def boolean(table: Table, key: str, where: str, default: bool) -> bool:
    value = table.get(key, default)
    if not isinstance(value, bool):
        raise ConfigError(f"{where}.{key}: {value!r} not allowed (allowed: true, false)")
    return value


def array(table: Table, key: str, where: str) -> list[object]:
    value = table.get(key, [])
    if not isinstance(value, list):
        raise ConfigError(f"{where}.{key}: {value!r} is not a list")
    return value
