"""``fieldtwin tesis`` commands, non-interactive."""

from __future__ import annotations

import json
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
