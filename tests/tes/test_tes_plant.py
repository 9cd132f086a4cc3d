"""[[tes]] plant tables: validation with field paths, inputs, faults."""

from __future__ import annotations

import sqlite3
from pathlib import Path
from typing import Any

import pytest

from fieldtwin.clock import SimClock
from fieldtwin.errors import ConfigError
from fieldtwin.facade.tes import build_tes, line_settings
from fieldtwin.modbus.model import Link
from fieldtwin.tes import Tes
from fieldtwin.transports.url import parse_endpoint

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


def test_3_1_4_slave_is_the_number_on_the_port_link_names(tmp_path: Path) -> None:
    """§3.1.3 / §3.1.4: each port has its own slave number; `slave` sets the one of `link`."""
    table = {"model": "TES 8ESA", "slave": 7, "endpoint": "pty", "link": "rs232"}
    (tes,) = _build(tmp_path, table)
    assert (tes.slave_for(Link.RS232), tes.slave_for(Link.RS485)) == (7, 1)
    assert tes.slave == 7 and tes.link is Link.RS232
    assert tes.eeprom()["rs232.slave"] == 7
    (rs485,) = _build(tmp_path, {**table, "link": "rs485"})
    assert (rs485.slave_for(Link.RS232), rs485.slave_for(Link.RS485)) == (1, 7)


def test_an_absent_slave_keeps_the_eeprom_number(tmp_path: Path) -> None:
    store = tmp_path / "eeprom.db"
    Tes("TES 32ST", store=store, name="st").write_eeprom({"rs485.slave": 12, "rs232.slave": 5})
    table = {"model": "TES 32ST", "endpoint": "pty", "store": "eeprom.db", "name": "st"}
    (tes,) = _build(tmp_path, table)
    assert tes.slave == 12
    (on_232,) = _build(tmp_path, {**table, "link": "rs232"})
    assert on_232.slave == 5
    (fresh,) = _build(tmp_path, {"model": "TES 32ST", "endpoint": "pty"})
    assert fresh.slave == 1  # §3.1.2 factory slave 1


def test_one_endpoint_is_one_port(tmp_path: Path) -> None:
    a = {"model": "TES 8EA", "slave": 4, "endpoint": "pty"}
    b = {"model": "TES 32ST", "slave": 5, "endpoint": "pty", "link": "rs232"}
    with pytest.raises(
        ConfigError, match=r"^plant\.toml: tes\[1\]\.link: rs232 on pty, where tes\[0\] is on rs485"
    ):
        _build(tmp_path, a, b)
    a["link"] = "rs232"
    assert len(_build(tmp_path, a, b)) == 2


def test_3_1_4_an_rs232_line_takes_the_rs232_format(tmp_path: Path) -> None:
    """§3.1.4 speed and parity of the RS-232 port; 8 data bits and 1 stop bit are fixed."""
    store = tmp_path / "eeprom.db"
    Tes("TES 8ESA", store=store, name="esa").write_eeprom(
        {"rs232.baud": 19200, "rs232.parity": "O", "rs485.baud": 4800}
    )
    table = {"model": "TES 8ESA", "endpoint": "pty", "link": "rs232", "store": "eeprom.db"}
    (tes,) = _build(tmp_path, {**table, "name": "esa"})
    settings = line_settings(parse_endpoint("pty"), [tes], Link.RS232)
    assert (settings.baud, settings.data_bits, settings.parity.letter, settings.stop_bits) == (
        19200, 8, "O", 1,
    )  # fmt: skip
    with pytest.raises(ConfigError, match=r"rs232\.baud / rs232\.parity"):
        line_settings(parse_endpoint("pty?baud=9600&parity=E"), [tes], Link.RS232)


@pytest.mark.parametrize(
    ("endpoint", "message"),
    [
        ("pty?baud=38400&parity=E&data=7", r"data=7 not allowed: a TES port has 8 data bits"),
        ("serial:///dev/ttyUSB0?baud=38400&parity=E&stop=2", r"stop=2 not allowed"),
    ],
)
def test_3_1_3_eight_data_bits_and_one_stop_bit_are_fixed(
    tmp_path: Path, endpoint: str, message: str
) -> None:
    """Issue 10 item 10: refused like a wrong speed or parity."""
    table = {"model": "TES 32EST", "endpoint": endpoint}
    with pytest.raises(ConfigError, match=rf"^plant\.toml: tes\[0\]\.endpoint: {message}"):
        _build(tmp_path, table)
    assert len(_build(tmp_path, {**table, "endpoint": "pty?baud=38400&parity=E&data=8&stop=1"}))


def test_a_foreign_sqlite_store_is_refused_and_left_alone(tmp_path: Path) -> None:
    """Issue 10 items 6 and 7: a clear error naming the file, never a traceback."""
    foreign = tmp_path / "shop.db"
    with sqlite3.connect(foreign) as db:
        db.execute("CREATE TABLE orders (id INTEGER)")
    before = foreign.read_bytes()
    table = {"model": "TES 8EA", "endpoint": "pty", "store": "shop.db"}
    with pytest.raises(
        ConfigError,
        match=r"^plant\.toml: tes\[0\]: TES parameter store .*shop\.db: not a fieldtwin",
    ):
        _build(tmp_path, table)
    assert foreign.read_bytes() == before
    (tmp_path / "notes.db").write_text("not a database\n")
    with pytest.raises(ConfigError, match=r"notes\.db: not a fieldtwin TES store"):
        _build(tmp_path, {**table, "store": "notes.db"})


def test_a_store_value_that_is_not_json_is_named(tmp_path: Path) -> None:
    Tes("TES 8EA", store=tmp_path / "e.db", name="boiler")
    with sqlite3.connect(tmp_path / "e.db") as db:
        db.execute("UPDATE eeprom SET value = '{oops' WHERE param = 'ai0.filter'")
    table = {"model": "TES 8EA", "endpoint": "pty", "store": "e.db", "name": "boiler"}
    with pytest.raises(
        ConfigError,
        match=r"e\.db: device 'boiler' parameter 'ai0\.filter': '\{oops' is not a JSON value",
    ):
        _build(tmp_path, table)


def test_plant_level_beyond_the_span_saturates(tmp_path: Path) -> None:
    """Issue 10 item 13 through the API the plant layer calls: the note says so."""
    (tes,) = _build(tmp_path, {"model": "TES 8EA", "endpoint": "pty", "inputs": {"a0": 15.0}})
    tes.advance(1.0)
    assert tes.peek(0x003) == 1023
