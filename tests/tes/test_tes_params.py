"""§1 / §3 the EEPROM: persistence, the power-on rule, the Prm jumper, validation."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fieldtwin.errors import ConfigError
from fieldtwin.modbus.model import Link
from fieldtwin.tes import Tes
from fieldtwin.tes.models import MODELS
from fieldtwin.tes.params import factory
from fieldtwin.tes.store import ParameterStore

from .helpers import read_word, write_word


def test_section_1_online_changes_last_until_the_next_power_on(tmp_path: Path) -> None:
    tes = Tes("TES 32EST", store=tmp_path / "eeprom.db")
    write_word(tes, 0x00B, 100)
    tes.advance(10.0)
    assert read_word(tes, 0x00B) == 100
    tes.power_cycle()
    assert read_word(tes, 0x00B) == 1


def test_eeprom_persists_in_the_sqlite_file(tmp_path: Path) -> None:
    path = tmp_path / "plant.db"
    first = Tes("TES 8EA", slave=9, store=path, name="boiler")
    first.write_eeprom({"filter_1_ms": 50, "ai3.filter": 64})
    first.store.close()
    again = Tes("TES 8EA", store=path, name="boiler")
    assert again.slave == 9
    assert read_word(again, 0x01E) == 10  # 50 ms in steps of 5 ms
    assert again.params["ai3.filter"] == 64


def test_eeprom_changes_take_effect_at_power_on_only() -> None:
    tes = Tes("TES 16EST")
    tes.write_eeprom({"filter_0_ms": 100})
    assert read_word(tes, 0x00A) == 1
    tes.power_cycle()
    assert read_word(tes, 0x00A) == 20


def test_3_1_2_prm_jumper_gives_the_factory_settings() -> None:
    tes = Tes("TES 8EA", slave=12, prm_jumper=True)
    tes.write_eeprom({"filter_0_ms": 100, "watchdog_100ms": 30})
    tes.power_cycle()
    assert tes.slave == 1  # Modbus/Jbus slave 1
    assert tes.params["rs485.baud"] == 38400 and tes.params["rs232.baud"] == 9600
    assert tes.params["rs485.parity"] == "E" and tes.params["rs232.parity"] == "E"
    assert read_word(tes, 0x01D) == 1  # filtering 5 ms
    assert (read_word(tes, 0x01F), read_word(tes, 0x021)) == (100, 10)  # 1 Hz and 10 Hz
    assert read_word(tes, 0x03D) == 0  # outputs fall back to 0
    assert read_word(tes, 0x046) == 0  # no analog fallback
    assert tes.leds["Prm"] == "on"
    tes.prm_jumper = False
    tes.power_cycle()
    assert tes.slave == 12 and read_word(tes, 0x01D) == 20


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("rs485.slave", 300, r"rs485.slave: 300 out of range \(allowed 1..247\)"),
        ("rs485.baud", 14400, r"rs485.baud: 14400 is not allowed \(allowed: 1200, .*38400\)"),
        ("rs232.parity", "X", r"rs232.parity: 'X' is not allowed \(allowed: N, E, O\)"),
        ("rs485.answer_delay_ms", 2571, r"allowed 0..2570"),
        (
            "filter_0_ms",
            7,
            r"filter_0_ms: 7 is not a multiple of 5 \(allowed 0..32765 by steps of 5\)",
        ),
        ("ai0.filter", 3, r"allowed: 2, 4, 8, 16, 32, 64, 128, 256"),
        ("ai0.out_high", 4, r"allowed -1..3"),
        ("nonsense", 1, r"TES 8EA has no parameter 'nonsense'"),
    ],
)
def test_invalid_parameters_are_refused_with_the_allowed_range(
    name: str, value: object, message: str
) -> None:
    tes = Tes("TES 8EA")
    before = tes.eeprom()
    with pytest.raises(ConfigError, match=message):
        tes.write_eeprom({name: value})
    assert tes.eeprom() == before


def test_4_2_6_threshold_example_overloaded() -> None:
    tes = Tes("TES 8EA")
    scale = {"ai0.scale": "on", "ai0.scale_min": -100, "ai0.scale_max": 15000}
    tes.write_eeprom({**scale, "ai0.threshold": "simple", "ai0.low": 0, "ai0.high": 12602})
    with pytest.raises(ConfigError, match=r"ai0.low: -200 overloaded \(allowed -100..15000"):
        tes.write_eeprom({"ai0.low": -200})


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"ai0.threshold": "high_low", "ai0.out_high": 1, "ai0.out_low": 1}, "two different"),
        ({"ai0.threshold": "hysteresis"}, "hysteresis needs one reflex output"),
        ({"ai0.threshold": "simple", "ai0.out_low": 2}, "simple thresholds have no output"),
        ({"ai0.threshold": "simple", "ai0.low": 900, "ai0.high": 800}, "must be below"),
        (
            {
                "ai0.threshold": "hysteresis",
                "ai0.out_high": 2,
                "ai1.threshold": "hysteresis",
                "ai1.out_high": 2,
            },
            "output 2 is already driven by ai0",
        ),
        ({"ai0.scale": "on", "ai0.scale_min": 5, "ai0.scale_max": 5}, "must differ"),
    ],
)
def test_4_2_6_threshold_rules(values: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        Tes("TES 8EA").write_eeprom(values)


def test_an_interrupted_write_keeps_the_previous_contents(tmp_path: Path) -> None:
    tes = Tes("TES 32ET", store=tmp_path / "e.db")
    tes.write_eeprom({"filter_0_ms": 10})
    before = tes.store.load(tes.name)

    def fail(param: str) -> None:
        if param == "filter_1_ms":
            raise OSError("power lost during the write")

    new = {**tes.eeprom(), "filter_0_ms": 500, "filter_1_ms": 500}
    with pytest.raises(OSError):
        tes.store.save(tes.name, tes.model.name, new, before_row=fail)
    assert tes.store.load(tes.name) == before
    reopened = ParameterStore(tmp_path / "e.db")
    assert reopened.load(tes.name)["filter_0_ms"] == 10


def test_a_store_holding_another_model_is_refused() -> None:
    store = ParameterStore()
    Tes("TES 8EA", store=store, name="x")
    with pytest.raises(ConfigError, match="holds a TES 8EA, not a TES 4EA"):
        Tes("TES 4EA", store=store, name="x")


def test_slave_numbers_per_link() -> None:
    tes = Tes("TES 32ST", slave=5)
    tes.write_eeprom({"rs232.slave": 7})
    tes.power_cycle()
    assert (tes.slave_for(Link.RS485), tes.slave_for(Link.RS232)) == (5, 7)


@pytest.mark.parametrize("model", list(MODELS))
def test_factory_settings_are_valid_for_every_model(model: str) -> None:
    values = factory(MODELS[model])
    tes = Tes(model)
    assert tes.eeprom() == values


def test_a_store_written_before_the_application_id_still_opens(tmp_path: Path) -> None:
    """Stores of earlier versions (no application id, the two tables) keep working."""
    old = tmp_path / "old.db"
    with sqlite3.connect(old) as db:
        db.executescript(
            "CREATE TABLE device (name TEXT PRIMARY KEY, model TEXT NOT NULL);"
            "CREATE TABLE eeprom (device TEXT NOT NULL REFERENCES device(name),"
            " param TEXT NOT NULL, value TEXT NOT NULL, PRIMARY KEY (device, param));"
            "INSERT INTO device VALUES ('st', 'TES 32ST');"
            "INSERT INTO eeprom VALUES ('st', 'rs485.slave', '12');"
        )
    assert ParameterStore(old, readonly=True).load("st") == {"rs485.slave": 12}
    assert Tes("TES 32ST", store=old, name="st").slave == 12
    (tmp_path / "empty.db").touch()  # what an older `tesis show` left behind
    assert ParameterStore(tmp_path / "empty.db", readonly=True).devices() == {}
    assert Tes("TES 32ST", store=tmp_path / "empty.db").slave == 1


def test_a_read_only_store_writes_nothing(tmp_path: Path) -> None:
    Tes("TES 32ST", store=tmp_path / "e.db", name="st")
    store = ParameterStore(tmp_path / "e.db", readonly=True)
    with pytest.raises(ConfigError, match=r"e\.db: opened read-only"):
        store.save("st", "TES 32ST", {})
    with pytest.raises(ConfigError, match=r"e\.db: no device 'other' \(devices stored: 'st'"):
        Tes("TES 32ST", store=store, name="other")
    assert Tes("TES 32ST", store=store, name="st").slave == 1


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(value=st.text(max_size=12), param=st.sampled_from(["ai0.filter", "rs485.slave", "bogus"]))
def test_any_stored_value_gives_a_tes_or_an_error_naming_the_store(
    tmp_path: Path, value: str, param: str
) -> None:
    """Issue 10 item 6: whatever a store row holds, a clear error and never a traceback."""
    db = tmp_path / "p.db"
    db.unlink(missing_ok=True)
    Tes("TES 8EA", store=db, name="t")
    with sqlite3.connect(db) as conn:
        conn.execute("INSERT OR REPLACE INTO eeprom VALUES ('t', ?, ?)", (param, value))
    try:
        Tes("TES 8EA", store=db, name="t")
    except ConfigError as exc:
        assert str(db) in str(exc)


@pytest.mark.parametrize(
    "script",
    [
        "CREATE TABLE device (name TEXT, colour TEXT); CREATE TABLE eeprom (a, b, c);",
        "CREATE TABLE device (name TEXT PRIMARY KEY, model TEXT NOT NULL);"
        "CREATE TABLE eeprom (device TEXT, param TEXT, value TEXT); CREATE TABLE extra (x);",
        "PRAGMA application_id = 42;",
    ],
)
def test_a_database_that_is_not_a_store_is_refused(tmp_path: Path, script: str) -> None:
    db = tmp_path / "x.db"
    with sqlite3.connect(db) as conn:
        conn.executescript(script)
    for readonly in (False, True):
        with pytest.raises(ConfigError, match=rf"{db}: not a fieldtwin TES store"):
            ParameterStore(db, readonly=readonly)


def test_a_filter_off_the_5_ms_step_says_multiple_of_5() -> None:
    # issue 10 item 21: `set filter_0_ms 7` said "out of range"
    from fieldtwin.errors import ConfigError
    from fieldtwin.tes.models import model_named
    from fieldtwin.tes.params import param_specs

    spec = param_specs(model_named("TES 32EST"))["filter_0_ms"]
    with pytest.raises(ConfigError, match=r"filter_0_ms: 7 is not a multiple of 5"):
        spec.parse("7")
    with pytest.raises(ConfigError, match=r"filter_0_ms: 40000 out of range"):
        spec.parse("40000")
