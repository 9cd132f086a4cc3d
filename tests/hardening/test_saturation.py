"""TES analog levels beyond the converter's span saturate and are said so (issue 10 item 13)."""

from __future__ import annotations

from pathlib import Path

from tests.hardening.test_cli_errors import fieldtwin

PLANT = (
    '[[tes]]\nmodel = "TES 8EA"\nslave = 2\nendpoint = "tcp://127.0.0.1:0"\n'
    "inputs = { a0 = 15.0 }\n"
)


def test_plant_and_console_say_when_a_level_saturates(tmp_path: Path) -> None:
    (tmp_path / "plant.toml").write_text(PLANT)
    done = fieldtwin(
        ["console", "plant.toml", "-c", "tes 2 input a1 -5", "-c", "tes 2 peek H'00C'"], tmp_path
    )
    assert done.returncode == 0, done.stderr
    assert "fieldtwin: note: plant.toml: tes[0].inputs.a0: TES 8EA analog input a0: 15 V" in (
        done.stderr
    )
    assert "saturated, it reads as 1023 points" in done.stderr
    out = done.stdout.splitlines()
    assert out[0] == "tes 2 input a1 = -5"
    assert (
        out[1].startswith("note: TES 8EA analog input a1: -5 V is outside") and "0 points" in out[1]
    )
