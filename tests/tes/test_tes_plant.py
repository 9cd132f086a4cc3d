"""[[tes]] plant tables: validation with field paths, inputs, faults."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from fieldtwin.clock import SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.tes.plant import build_tes

from .helpers import pair, read_word


def _build(tmp_path: Path, *tables: dict[str, Any]) -> list[Any]:
    return build_tes(list(tables), SimClock(), "plant.toml", tmp_path)


P = "pty"


@pytest.mark.parametrize(
    ("table", "message"),
    [
        (
            {"model": "TES 8EA", "slave": 300, "endpoint": "pty"},
            r"tes\[0\]\.slave: 300 out of range \(allowed 1..247\)",
        ),
        (
            {"model": "TES 9X", "endpoint": "pty"},
            r"tes\[0\]\.model: unknown TES model 'TES 9X' \(allowed: TES 16EST",
        ),
        ({"slave": 1, "endpoint": "pty"}, r"tes\[0\]\.model: missing"),
        ({"model": "TES 8EA", "endpoint": "ftp://x"}, r"tes\[0\]\.endpoint: endpoint 'ftp://x'"),
        ({"model": "TES 8EA"}, r"tes\[0\]\.endpoint: missing"),
        (
            {"model": "TES 8EA", "endpoint": "pty", "colour": 1},
            r"tes\[0\]: unknown key\(s\) colour",
        ),
        (
            {"model": "TES 8EA", "endpoint": "pty", "prm_jumper": "yes"},
            r"tes\[0\]\.prm_jumper: 'yes' not allowed",
        ),
        (
            {"model": "TES 8EA", "endpoint": "pty", "link": "can"},
            r"tes\[0\]\.link: 'can' not allowed",
        ),
        (
            {"model": "TES 8EA", "endpoint": "pty", "inputs": {"a9": 1.0}},
            r"tes\[0\]\.inputs\.a9: .*no analog input 9",
        ),
        (
            {"model": "TES 8EA", "endpoint": "pty", "inputs": {"x": 1.0}},
            r"tes\[0\]\.inputs\.x: not an input",
        ),
        (
            {"model": "TES 8EA", "endpoint": "pty", "inputs": {"a0": {"kind": "zigzag"}}},
            r"tes\[0\]\.inputs\.a0\.kind: unknown signal kind",
        ),
        (
            {"model": "TES 32ET", "endpoint": "pty", "faults": {"short": [1]}},
            r"tes\[0\]\.faults\.short: .*only the TES 32ET-S",
        ),
        (
            {"model": "TES 32ET", "endpoint": "pty", "faults": {"fire": 1}},
            r"tes\[0\]\.faults: unknown key\(s\) fire",
        ),
    ],
)
def test_errors_name_the_field_path(tmp_path: Path, table: dict[str, Any], message: str) -> None:
    with pytest.raises(ConfigError, match=rf"^plant\.toml: {message}"):
        _build(tmp_path, table)


def test_two_tes_with_one_number_on_one_line_are_refused(tmp_path: Path) -> None:
    a = {"model": "TES 8EA", "slave": 4, "endpoint": "rtu+tcp://127.0.0.1:5021"}
    b = {"model": "TES 32ST", "slave": 4, "endpoint": "rtu+tcp://127.0.0.1:5021"}
    with pytest.raises(ConfigError, match=r"tes\[1\]\.slave: 4 already answers on rtu\+tcp"):
        _build(tmp_path, a, b)
    b["endpoint"] = "rtu+tcp://127.0.0.1:5022"
    assert len(_build(tmp_path, a, b)) == 2


def test_inputs_constants_and_signals(tmp_path: Path) -> None:
    table = {
        "model": "TES 8ESA",
        "slave": 2,
        "endpoint": "pty",
        "inputs": {
            "0": True,
            "a1": 5.0,
            "1": {"kind": "pulse", "period_s": 0.1, "duty": 0.5},
        },
    }
    (tes,) = _build(tmp_path, table)
    tes.advance(1.0)
    assert read_word(tes, 0x001) & 1 == 1
    assert read_word(tes, 0x004) == 512
    assert pair(tes, 0x421) == 10


def test_store_prm_jumper_and_faults(tmp_path: Path) -> None:
    table = {
        "model": "TES 32ET-S",
        "slave": 9,
        "endpoint": "serial:///dev/ttyUSB0?baud=38400&parity=E",
        "store": "eeprom.db",
        "name": "line-a",
        "faults": {"open": [2], "not_ready_ms": 1.5},
    }
    (tes,) = _build(tmp_path, table)
    assert (tmp_path / "eeprom.db").exists()
    assert tes.slave == 9 and tes.name == "line-a"
    assert tes.not_ready_window_us == 1500
    assert tes.di.wiring(2).value == "open"
    (jumpered,) = _build(tmp_path, {**table, "prm_jumper": True})
    assert jumpered.slave == 1


def test_an_unpowered_tes(tmp_path: Path) -> None:
    (tes,) = _build(tmp_path, {"model": "TES 4SA", "endpoint": "pty", "faults": {"powered": False}})
    assert not tes.powered
