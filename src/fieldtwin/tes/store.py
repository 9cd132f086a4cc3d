"""The TES EEPROM, persisted in SQLite (DESIGN rule 10).

One file may hold the EEPROMs of several TES, each under a device name.
Writing a whole configuration is one transaction: a write interrupted half way
keeps the previous contents (DESIGN rule 9).
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Callable, Mapping
from pathlib import Path

from fieldtwin.errors import ConfigError
from fieldtwin.tes.params import Value

_SCHEMA = """
CREATE TABLE IF NOT EXISTS device (name TEXT PRIMARY KEY, model TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS eeprom (
    device TEXT NOT NULL REFERENCES device(name),
    param TEXT NOT NULL,
    value TEXT NOT NULL,
    PRIMARY KEY (device, param)
);
"""


class ParameterStore:
    """EEPROM contents by device name; ``path=None`` keeps them in memory."""

    def __init__(self, path: str | Path | None = None) -> None:
        self.path = None if path is None else Path(path)
        target = ":memory:" if self.path is None else str(self.path)
        try:
            self._db = sqlite3.connect(target, isolation_level=None)
            self._db.executescript(_SCHEMA)
        except sqlite3.Error as exc:
            raise ConfigError(f"TES parameter store {target}: {exc}") from None

    def close(self) -> None:
        self._db.close()

    def devices(self) -> dict[str, str]:
        """device name -> model name."""
        rows = self._db.execute("SELECT name, model FROM device ORDER BY name").fetchall()
        return {str(name): str(model) for name, model in rows}

    def model_of(self, device: str) -> str | None:
        return self.devices().get(device)

    def load(self, device: str) -> dict[str, Value]:
        rows = self._db.execute(
            "SELECT param, value FROM eeprom WHERE device = ? ORDER BY param", (device,)
        ).fetchall()
        return {str(param): _decode(str(value)) for param, value in rows}

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
        db = self._db
        db.execute("BEGIN IMMEDIATE")
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


def _decode(text: str) -> Value:
    value = json.loads(text)
    if isinstance(value, bool) or not isinstance(value, int | str):
        raise ConfigError(f"TES parameter store holds {text!r}, not an int or a string")
    return value
