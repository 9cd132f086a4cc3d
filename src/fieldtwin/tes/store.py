"""The TES EEPROM, persisted in SQLite (DESIGN rule 10).

One file may hold the EEPROMs of several TES, each under a device name.
Writing a whole configuration is one transaction: a write interrupted half way
keeps the previous contents (DESIGN rule 9).

A store is marked with its own SQLite ``application_id``; a file that is not
SQLite, or an SQLite database with other tables, is refused with an error
naming the file, and is never written.  ``readonly=True`` (the read-only
``tesis`` commands) never creates a file nor writes a row.  Without a path
the store is a plain dictionary (no SQLite: a thousand TES start fast).
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Callable, Mapping
from pathlib import Path

from fieldtwin.errors import ConfigError
from fieldtwin.tes.params import Value

APPLICATION_ID = 0x46545345  # "FTSE": a fieldtwin TES EEPROM store
_TABLES = {"device": ("name", "model"), "eeprom": ("device", "param", "value")}
_SCHEMA = f"""
CREATE TABLE IF NOT EXISTS device (name TEXT PRIMARY KEY, model TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS eeprom (
    device TEXT NOT NULL REFERENCES device(name),
    param TEXT NOT NULL,
    value TEXT NOT NULL,
    PRIMARY KEY (device, param)
);
PRAGMA application_id = {APPLICATION_ID};
"""


class ParameterStore:
    """EEPROM contents by device name; ``path=None`` keeps them in memory."""

    def __init__(self, path: str | Path | None = None, *, readonly: bool = False) -> None:
        self.path = None if path is None else Path(path)
        self.readonly = readonly and self.path is not None
        self.where = "the in-memory store" if self.path is None else str(self.path)
        self._empty = True  # no tables yet (a new or empty file)
        self._memory: dict[str, tuple[str, dict[str, Value]]] | None = None
        self._connection: sqlite3.Connection | None = None
        if self.path is None:
            self._memory = {}  # device -> (model, values)
            return
        try:
            self._connection = self._connect()
        except sqlite3.Error as exc:
            raise ConfigError(f"TES parameter store {self.where}: {exc}") from None
        try:
            self._check()
        except BaseException:
            self._db.close()
            raise

    def _connect(self) -> sqlite3.Connection:
        assert self.path is not None
        if self.path.is_dir():
            raise ConfigError(f"TES parameter store {self.where}: is a directory")
        if self.readonly:
            if not self.path.exists():
                raise ConfigError(
                    f"TES parameter store {self.where}: no such file (a read-only command"
                    " creates none; `tesis --store FILE --model MODEL set|factory|import` does)"
                )
            uri = f"{self.path.resolve().as_uri()}?mode=ro"
            return sqlite3.connect(uri, uri=True, isolation_level=None)
        return sqlite3.connect(str(self.path), isolation_level=None)

    @property
    def _db(self) -> sqlite3.Connection:
        assert self._connection is not None, "an in-memory store has no database"
        return self._connection

    def _check(self) -> None:
        """Refuse a file that is not a fieldtwin store; create the tables in a new one."""
        try:
            app_id = self._db.execute("PRAGMA application_id").fetchone()[0]
            rows = self._db.execute(
                "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'"
            ).fetchall()
            tables = {str(name) for (name,) in rows}
            if app_id not in (0, APPLICATION_ID) or (tables and not self._ours(tables)):
                found = ", ".join(sorted(tables)) or "none"
                raise ConfigError(
                    f"TES parameter store {self.where}: not a fieldtwin TES store"
                    f" (SQLite application id {app_id:#x}, tables: {found}); give another file"
                )
            if not self.readonly and (not tables or app_id == 0):
                self._db.executescript(_SCHEMA)
        except sqlite3.Error as exc:
            raise ConfigError(
                f"TES parameter store {self.where}: not a fieldtwin TES store ({exc})"
            ) from None
        self._empty = not tables

    def _ours(self, tables: set[str]) -> bool:
        if tables != set(_TABLES):
            return False
        for table, columns in _TABLES.items():
            info = self._db.execute(f"PRAGMA table_info({table})").fetchall()
            if tuple(str(row[1]) for row in info) != columns:
                return False
        return True

    def close(self) -> None:
        if self._memory is None:
            self._db.close()

    def _query(self, sql: str, args: tuple[str, ...] = ()) -> list[tuple[object, ...]]:
        if self._empty and self.readonly:
            return []  # an empty SQLite file opened read-only: no tables yet
        try:
            return self._db.execute(sql, args).fetchall()
        except sqlite3.Error as exc:
            raise ConfigError(f"TES parameter store {self.where}: {exc}") from None

    def devices(self) -> dict[str, str]:
        """device name -> model name."""
        if self._memory is not None:
            return {name: self._memory[name][0] for name in sorted(self._memory)}
        rows = self._query("SELECT name, model FROM device ORDER BY name")
        return {str(name): str(model) for name, model in rows}

    def model_of(self, device: str) -> str | None:
        return self.devices().get(device)

    def describe_devices(self) -> str:
        """``boiler (TES 8EA), pump (TES 32ST)``, or ``none``."""
        devices = self.devices()
        return ", ".join(f"{name!r} ({model})" for name, model in devices.items()) or "none"

    def no_device(self, device: str) -> str:
        """The message for a device name the store does not hold."""
        return (
            f"TES parameter store {self.where}: no device {device!r}"
            f" (devices stored: {self.describe_devices()})"
        )

    def load(self, device: str) -> dict[str, Value]:
        if self._memory is not None:
            _, values = self._memory.get(device, ("", {}))
            return dict(sorted(values.items()))
        rows = self._query(
            "SELECT param, value FROM eeprom WHERE device = ? ORDER BY param", (device,)
        )
        return {str(param): self._decode(device, str(param), value) for param, value in rows}

    def _decode(self, device: str, param: str, raw: object) -> Value:
        where = f"TES parameter store {self.where}: device {device!r} parameter {param!r}"
        try:
            value = json.loads(raw) if isinstance(raw, str | bytes) else raw
        except ValueError:
            raise ConfigError(f"{where}: {raw!r} is not a JSON value") from None
        if isinstance(value, bool) or not isinstance(value, int | str):
            raise ConfigError(f"{where}: holds {raw!r}, not an int or a string")
        return value

    def save(
        self,
        device: str,
        model: str,
        values: Mapping[str, Value],
        before_row: Callable[[str], None] | None = None,
    ) -> None:
        """Replace ``device``'s EEPROM by ``values`` in one transaction.

        ``before_row(param)`` runs before each row is written (tests inject a
        failure there to show an interrupted write loses nothing).
        """
        if self.readonly:
            raise ConfigError(f"TES parameter store {self.where}: opened read-only")
        if self._memory is not None:
            written: dict[str, Value] = {}
            for param, value in values.items():  # all or nothing, like the transaction
                if before_row is not None:
                    before_row(param)
                written[param] = value
            self._memory[device] = (model, written)
            return
        db = self._db
        try:
            db.execute("BEGIN IMMEDIATE")
        except sqlite3.Error as exc:
            raise ConfigError(f"TES parameter store {self.where}: {exc}") from None
        try:
            db.execute("INSERT OR REPLACE INTO device (name, model) VALUES (?, ?)", (device, model))
            db.execute("DELETE FROM eeprom WHERE device = ?", (device,))
            for param, value in values.items():
                if before_row is not None:
                    before_row(param)
                db.execute(
                    "INSERT INTO eeprom (device, param, value) VALUES (?, ?, ?)",
                    (device, param, json.dumps(value)),
                )
        except BaseException:
            db.execute("ROLLBACK")
            raise
        db.execute("COMMIT")
        self._empty = False
