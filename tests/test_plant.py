"""Plant files: building and every validation error naming the field path."""

from __future__ import annotations

from pathlib import Path

import pytest

import tests.tsx.double  # noqa: F401  registers the test double
from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from tests.tsx.double import DOUBLE


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "plant.toml"
    path.write_text(text)
    return path


def test_a_plant_builds_its_plc_and_modules(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        f"""
[plant]
name = "bench"
[plc]
model = "TSX 67"
scan_ms = 20
[[module]]
type = "{DOUBLE}"
rack = 1
slot = 2
faults = ["sensor"]
""",
    )
    plant = load_plant(path)
    assert plant.title == "bench" and plant.plc is not None
    assert plant.plc.model.name == "TSX 67" and plant.plc.scan_us == 20_000
    assert plant.plc.module(1, 2).type_name == DOUBLE
    plant.plc.advance(2.1)
    assert plant.plc.read("IW12,0,7") == 1  # the fault from the plant file


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[plc]\nmodel = 'TSX 99'", "plant.toml: plc.model: 'TSX 99' not allowed (allowed: TSX"),
        ("[plc]\nscan_ms = 0", "plant.toml: plc.scan_ms: 0 not allowed (allowed 1..1000 ms)"),
        (
            "[plc]\nspeed = 3",
            "plant.toml: plc: unknown key(s) speed (allowed: model, scan_ms, outputs)",
        ),
        ("[plcs]\n", "plant.toml: unknown top-level key(s) plcs (allowed: plant, plc, module"),
        ("[[module]]\nslot = 3", "plant.toml: module[0].type: missing or not a string"),
        (f"[[module]]\ntype = '{DOUBLE}'", "plant.toml: module[0].slot: missing"),
        (f"[[module]]\ntype = '{DOUBLE}'\nslot = 'x'", "module[0].slot: 'x' is not an integer"),
        (f"[[module]]\ntype = '{DOUBLE}'\nslot = 9", "module[0].slot: slot 9 cannot take"),
        ("[[module]]\ntype = 'TSX FOO'\nslot = 1", "module[0].type: unknown module type 'TSX FOO'"),
        (
            f"[[module]]\ntype = '{DOUBLE}'\nslot = 1\ncolour = 'red'",
            "plant.toml: module[0]: unknown keys ['colour']",
        ),
        (
            f"[[module]]\ntype = '{DOUBLE}'\nslot = 1\nfaults = ['smoke']",
            "module[0]: unknown fault 'smoke'",
        ),
        ("[plc\n", "plant.toml: not valid TOML"),
        ("[run]\nspeed = -1", "plant.toml: run.speed: -1 not allowed"),
        (
            f"[plc]\noutputs = {{ 'IW5,0' = 1 }}\n[[module]]\ntype = '{DOUBLE}'\nslot = 5",
            "plant.toml: plc.outputs.'IW5,0': 'IW5,0' is an input",
        ),
        ("[plc]\noutputs = { 'OW5,0,C' = 1 }", "plc.outputs.'OW5,0,C': no module in rack 0 slot 5"),
    ],
)
def test_validation_errors_name_the_field(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        load_plant(write(tmp_path, text))
    assert message in str(info.value)


def test_initial_outputs_put_a_module_in_run(tmp_path: Path) -> None:
    text = f"[plc]\noutputs = {{ 'OW5,0,C' = 1 }}\n[[module]]\ntype = '{DOUBLE}'\nslot = 5\n"
    plant = load_plant(write(tmp_path, text))
    assert plant.plc is not None
    plant.plc.advance(2.1)
    assert plant.plc.read("IW5,0,C") == 1


def test_missing_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"nope\.toml: cannot read the plant file"):
        load_plant(tmp_path / "nope.toml")


def test_speed_from_the_plant_file(tmp_path: Path) -> None:
    assert load_plant(write(tmp_path, "[run]\nspeed = 'max'\n[plc]\n")).speed is None
    assert load_plant(write(tmp_path, "[run]\nspeed = 10\n[plc]\n")).speed == 10.0


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            f"[[module]]\ntype = '{DOUBLE}'\nrack = 9\nslot = 1",
            "module[0].rack: rack 9 out of range",
        ),
        ("[run]\nspeed = nan", "run.speed: nan not allowed"),
        ("[run]\nspeed = inf", "run.speed: inf not allowed"),
        ("[run]\nsped = 10", "plant.toml: run: unknown key(s) sped (allowed: speed)"),
    ],
)
def test_more_validation_errors_name_the_field(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        load_plant(write(tmp_path, text))
    assert message in str(info.value)
