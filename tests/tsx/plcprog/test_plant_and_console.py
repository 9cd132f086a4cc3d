"""The program in a plant file, in the console and through `fieldtwin run` (issue 13)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from fieldtwin.console import Console
from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant

ROOT = Path(__file__).resolve().parents[3]


def test_plant_key_program_constants_and_text_blocks() -> None:
    plant = load_plant(ROOT / "examples" / "aem811_tank.toml", speed=None)
    try:
        assert plant.plc is not None and plant.plc.program is not None
        assert plant.plc.read("CW1") == 30 and plant.plc.read("CW108") == 8000
        plant.plc.advance(12.0)
        assert [plant.plc.read(f"W{i}") for i in range(4)] == [5001] * 4
        assert plant.plc.read("IW5,0,C") == 1
    finally:
        plant.close()


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ('program = "missing.pl7"', "plc.program: .*missing.pl7: cannot read"),
        ('program = "bad.pl7"', r"plc.program: .*bad.pl7: line 2, column 10: 'CW1'"),
        ("constants = { W0 = [1] }", r"plc.constants.W0: 'W0' is not a word address"),
        ('text_blocks = { TXT0 = { indirect = "CW20" } }', "text_blocks.TXT0.indirect"),
        ('date = "yesterday"', "plc.date: 'yesterday' is not a date"),
    ],
)
def test_program_keys_refused_with_the_field(tmp_path: Path, line: str, message: str) -> None:
    (tmp_path / "bad.pl7").write_text("%PRE\n!     0->CW1\n")
    plant = tmp_path / "p.toml"
    plant.write_text(f"[plc]\n{line}\n")
    with pytest.raises(ConfigError, match=message):
        load_plant(plant, speed=None)


def test_console_prog_commands_stop_step_and_run() -> None:
    plant = load_plant(ROOT / "examples" / "dem24_assembly.toml", speed=None)
    try:
        console = Console(plant)
        console.execute("advance 12")
        assert console.execute("read X0 X1 W186 B11") == ["X0 = 1", "X1 = 0", "W186 = 0", "B11 = 0"]
        assert console.execute("prog stop-at-step 1") == ["stop at step 1"]
        console.execute("input 2 0 1")
        console.execute("advance 1")
        shown = console.execute("prog show")
        assert shown[0].startswith("program held: step 1 activated")
        assert "active steps: 1" in shown
        cycles = plant.plc.program.cycles if plant.plc and plant.plc.program else 0
        console.execute("prog step")
        assert plant.plc is not None and plant.plc.program is not None
        assert plant.plc.program.cycles == cycles + 1 and plant.plc.program.held is not None
        console.execute("prog clear")
        console.execute("prog run")
        console.execute("input 2 1 1")
        console.execute("advance 0.5")
        assert console.execute("read X2") == ["X2 = 1"]
        assert console.execute("write W20 5") == ["W20 = 5"]
        with pytest.raises(ConfigError, match="not a label"):
            console.execute("prog stop-at 12")
        held = console.execute("prog stop-at POST:L40")
        console.execute("advance 0.1")
        assert held == ["stop at POST L40"]
        assert any(">> !L40 :" in line for line in console.execute("prog show"))
    finally:
        plant.close()


def test_fieldtwin_run_runs_the_tank_program_as_a_subprocess() -> None:
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "fieldtwin",
            "run",
            str(ROOT / "examples" / "aem811_tank.toml"),
            "--speed",
            "max",
            "--duration",
            "12",
            "--no-live",
            "--status-every",
            "11.5",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stdout.splitlines() if line.startswith("program running")]
    assert lines, done.stdout
    # W0..W3 the levels (5001 mm = H'1389'), W4..W7 the flows (16000 = H'3E80')
    assert lines[-1].endswith("W0..7 1389 1389 1389 1389 3E80 3E80 3E80 3E80"), lines[-1]
    assert "slot 5 TSX AEM 811: Run" in done.stdout


def test_fieldtwin_run_runs_the_assembly_program_as_a_subprocess() -> None:
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "fieldtwin",
            "run",
            str(ROOT / "examples" / "dem24_assembly.toml"),
            "--speed",
            "max",
            "--duration",
            "12",
            "--no-live",
            "--status-every",
            "11.5",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert any(
        line.startswith("program running") and "steps 0 " in line
        for line in done.stdout.splitlines()
    ), done.stdout
    assert "slot 4 TSX DEM 2412: Run" in done.stdout
