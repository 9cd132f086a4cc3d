"""``fieldtwin tesis`` commands, non-interactive."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pytest

from fieldtwin.tes import Tes
from fieldtwin.tes.store import ParameterStore
from fieldtwin.tes.tesis import main


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_models_lists_all_ten(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(capsys, "models")
    assert code == 0
    assert all(name in out for name in ("TES 16EST", "TES 32ET-S", "TES 8SA-U"))


def test_set_show_and_persist(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    db = str(tmp_path / "e.db")
    code, out, _ = _run(capsys, "--store", db, "--model", "TES 8EA", "set", "ai0.filter", "16")
    assert code == 0 and "ai0.filter = 16" in out
    code, out, _ = _run(capsys, "--store", db, "show", "--json")
    assert json.loads(out)["ai0.filter"] == 16
    code, out, _ = _run(capsys, "--store", db, "show")
    assert "rs485.baud" in out and "38400" in out


def test_set_refuses_an_invalid_value(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    db = str(tmp_path / "e.db")
    code, _, err = _run(capsys, "--store", db, "--model", "32ET", "set", "rs485.slave", "0")
    assert code == 2
    assert "rs485.slave: 0 out of range (allowed 1..247)" in err


def test_validate_reports_a_bad_store(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    db = tmp_path / "e.db"
    Tes("TES 8EA", store=db, name="t")
    values = ParameterStore(db).load("t")
    values.update({"ai1.threshold": "high_low", "ai1.out_high": 2, "ai1.out_low": 2})
    ParameterStore(db).save("t", "TES 8EA", values)  # written behind TESIS's back
    code, out, err = _run(capsys, "--store", str(db), "validate")
    assert code == 2 and "two different outputs" in err
    good = Tes("TES 32ST", store=tmp_path / "g.db")
    assert good.slave == 1
    code, out, _ = _run(capsys, "--store", str(tmp_path / "g.db"), "validate")
    assert code == 0 and "parameters valid" in out


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_export_and_import_round_trip(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], suffix: str
) -> None:
    db, copy = str(tmp_path / "a.db"), str(tmp_path / "b.db")
    file = str(tmp_path / f"eeprom{suffix}")
    _run(
        capsys,
        "--store",
        db,
        "--model",
        "TES 8ESA",
        "set",
        "ao5.fallback",
        "1234",
        "rs485.parity",
        "O",
    )
    assert _run(capsys, "--store", db, "export", file)[0] == 0
    assert _run(capsys, "--store", copy, "--model", "8ESA", "import", file)[0] == 0
    restored = Tes("TES 8ESA", store=copy)
    assert restored.eeprom() == Tes("TES 8ESA", store=db).eeprom()
    assert restored.eeprom()["ao5.fallback"] == 1234


def test_import_refuses_another_model(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    file = tmp_path / "x.json"
    file.write_text(json.dumps({"model": "TES 4EA", "parameters": {}}))
    code, _, err = _run(capsys, "--model", "TES 8EA", "import", str(file))
    assert code == 2 and "holds a TES 4EA, not a TES 8EA" in err


def test_iotest_shows_inputs_and_forces_outputs(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(
        capsys, "--model", "TES 8ESA", "iotest",
        "--input", "0=1", "--input", "a2=4.5", "--output", "3=1", "--output", "a4=16384",
    )  # fmt: skip
    assert code == 0
    assert "4.500" in out and " 460 " in out  # 4.5 V = 460 points
    assert "5.000" in out  # analog output No 4
    lines = [line for line in out.splitlines() if line.strip().startswith("│ 3 ")]
    assert any(line.split("│")[2].strip() == "1" for line in lines)


def test_iotest_refuses_a_missing_output(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _run(capsys, "--model", "TES 32ET", "iotest", "--output", "0=1")
    assert code == 2 and "no digital output 0" in err


def test_map_prints_every_word(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(capsys, "--model", "TES 32ST", "map")
    assert code == 0 and "016h" in out and "watchdog" in out


def test_without_a_model_the_error_says_what_to_give(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _run(capsys, "show")
    assert code == 2 and "give --model" in err


def test_a_read_only_command_creates_no_store(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 10 item 18: `tesis --store new.db show` fails and leaves no new.db."""
    for command in ("show", "validate", "iotest"):
        code, _, err = _run(capsys, "--store", str(tmp_path / "new.db"), command)
        assert code == 2 and "new.db: no such file (a read-only command creates none" in err
    code, _, _ = _run(
        capsys, "--store", str(tmp_path / "new.db"), "--model", "8EA", "export", "x.json"
    )
    assert code == 2
    assert list(tmp_path.iterdir()) == []


def test_a_read_only_command_stores_no_device(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "eeprom.db"
    Tes("TES 32ST", store=db, name="pump")
    before = ParameterStore(db).devices()
    code, _, err = _run(capsys, "--store", str(db), "--model", "TES 8EA", "--device", "x", "show")
    assert code == 2 and "no device 'x' (devices stored: 'pump' (TES 32ST))" in err
    ParameterStore(tmp_path / "empty.db")  # an empty store
    code, _, err = _run(capsys, "--store", str(tmp_path / "empty.db"), "--model", "8EA", "show")
    assert code == 2 and "holds no TES 'TES 8EA #1' (devices stored: none)" in err
    assert "`set`, `factory` or `import` with --model MODEL writes one" in err
    assert ParameterStore(db).devices() == before
    assert ParameterStore(tmp_path / "empty.db").devices() == {}
    code, out, _ = _run(capsys, "--store", str(db), "show")  # still the only one: no --device
    assert code == 0 and "pump (TES 32ST)" in out


def test_an_unknown_device_gets_the_stored_devices_as_a_hint(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "eeprom.db"
    Tes("TES 32ST", store=db, name="pump")
    Tes("TES 8EA", store=db, name="boiler")
    code, _, err = _run(capsys, "--store", str(db), "--device", "nosuch", "show")
    assert code == 2
    assert "no device 'nosuch' (devices stored: 'boiler' (TES 8EA), 'pump' (TES 32ST))" in err
    code, _, err = _run(capsys, "--store", str(db), "show")
    assert code == 2 and "holds several TES: give --device" in err
    code, out, _ = _run(capsys, "--store", str(db), "--device", "pump", "show")
    assert code == 0 and "pump (TES 32ST)" in out


@pytest.mark.parametrize("command", ["show", "set"])
def test_a_foreign_or_broken_store_is_named(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    foreign = tmp_path / "shop.db"
    with sqlite3.connect(foreign) as db:
        db.execute("CREATE TABLE orders (id INTEGER)")
    args = ["ai0.filter", "4"] if command == "set" else []
    code, _, err = _run(capsys, "--store", str(foreign), "--model", "8EA", command, *args)
    assert code == 2 and f"{foreign}: not a fieldtwin TES store" in err and "orders" in err
    db_path = tmp_path / "e.db"
    Tes("TES 8EA", store=db_path, name="boiler")
    with sqlite3.connect(db_path) as db:
        db.execute("UPDATE eeprom SET value = 'not json' WHERE param = 'ai0.filter'")
    code, _, err = _run(capsys, "--store", str(db_path), "show")
    assert code == 2 and f"{db_path}: device 'boiler' parameter 'ai0.filter'" in err


@pytest.mark.parametrize("word", ["no", "maybe", "banana", "2"])
def test_iotest_digital_values_are_boolean_words(
    capsys: pytest.CaptureFixture[str], word: str
) -> None:
    """Issue 10 item 16: `--input 0=no` is off; the rest is refused, naming the token."""
    code, out, err = _run(capsys, "--model", "TES 32EST", "iotest", "--input", f"0={word}")
    if word == "no":
        assert code == 0
        rows = [line for line in out.splitlines() if line.strip().startswith("│ 0 ")]
        assert rows[0].split("│")[2].strip() == "0"  # direct input 0 stays off
    else:
        assert code == 2 and f"iotest --input '0={word}': '{word}' is not on or off" in err


def test_iotest_analog_input_beyond_the_span_saturates_and_says_so(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, _ = _run(
        capsys, "--model", "TES 8EA", "iotest", "--input", "a0=15.0", "--input", "a1=-5"
    )
    assert code == 0
    assert "note: TES 8EA analog input a0: 15 V is outside the converter's 0..10 V" in out
    assert "a1: -5 V is outside" in out and "reads as 0 points" in out
    rows = {line.split("│")[1].strip(): line for line in out.splitlines() if "│ a" in line}
    assert rows["a0"].split("│")[3].strip() == "1023"


def test_import_value_errors_name_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 10 item 21."""
    file = tmp_path / "bad.json"
    file.write_text(json.dumps({"model": "TES 8EA", "parameters": {"ai0.filter": 3}}))
    code, _, err = _run(capsys, "--model", "TES 8EA", "import", str(file))
    assert code == 2 and f"import: {file}: ai0.filter: 3 is not allowed" in err
    file.write_text(json.dumps({"model": "TES 99", "parameters": {}}))
    code, _, err = _run(capsys, "--model", "TES 8EA", "import", str(file))
    assert code == 2 and f"import: {file}: model: unknown TES model 'TES 99'" in err


def test_map_with_a_model_needs_no_store(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, _ = _run(capsys, "--store", str(tmp_path / "none.db"), "--model", "4EA", "map")
    assert code == 0 and "history[3][119]" in out
    assert not (tmp_path / "none.db").exists()


def test_another_model_than_the_only_one_stored_asks_for_a_device(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    db = tmp_path / "eeprom.db"
    Tes("TES 32ST", store=db, name="pump")
    code, _, err = _run(capsys, "--store", str(db), "--model", "8EA", "set", "ai0.filter", "16")
    assert code == 2 and "holds 'pump', a TES 32ST, not a TES 8EA: give --device NAME" in err
    argv = ["--store", str(db), "--model", "8EA", "--device", "boiler", "set", "ai0.filter", "16"]
    assert _run(capsys, *argv)[0] == 0
    assert ParameterStore(db).devices() == {"boiler": "TES 8EA", "pump": "TES 32ST"}
