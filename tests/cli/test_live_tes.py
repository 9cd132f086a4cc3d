"""The terminal live view of a TES-only plant shows each terminal's inputs, outputs,
analog inputs and analog outputs at every width (80 columns too), and so do the plain
status lines (`--no-live`)."""

from __future__ import annotations

import io
import subprocess
import sys
from pathlib import Path

import pytest
from rich.console import Console as RichConsole

from fieldtwin.live import plain_status, render
from fieldtwin.plant import load_plant

PLANT = """
[plant]
name = "TES only"

[[tes]]
model = "TES 32EST"
slave = 1
endpoint = "tcp://127.0.0.1:0"
inputs = { 0 = true, 3 = true }

[[tes]]
model = "TES 8EA"
slave = 2
endpoint = "tcp://127.0.0.1:0"
inputs = { a0 = 7.5, a3 = 2.5 }

[[tes]]
model = "TES 4SA"
slave = 3
endpoint = "tcp://127.0.0.1:0"
"""


@pytest.mark.parametrize("width", [80, 120, 200])
def test_a_tes_only_plant_shows_its_values(tmp_path: Path, width: int) -> None:
    path = tmp_path / "tes.toml"
    path.write_text(PLANT)
    plant = load_plant(path, speed=None)
    try:
        plant.clock.advance(2_000_000)
        est, _, sa = plant.devices
        est.objects().write("H'00D'", 0x0005)  # outputs 0 and 2 fixed on (command[1])
        sa.objects().write("H'014'", 0x4000)  # analog output a0
        plant.clock.advance(100_000)
        screen = RichConsole(record=True, width=width, file=io.StringIO())
        screen.print(render(plant, []))
        text = screen.export_text().replace("\n", " ")
        volts = next(o for o in sa.status().outputs if o.name == "a0").text()
        if width < 104:
            assert "TES 1 values:  in H'0009'  out H'0005'" in text
        else:
            assert "in: 0000000000001001 (15..0)  out: 0000000000000101 (15..0)" in text
        assert "a0=7.500V" in text and "a3=2.500V" in text
        assert f"aout: a0={volts}" in " ".join(text.split()), text
        assert "(H'4000')" in text
        lines = plain_status(plant)
        assert any(line.endswith("in H'0009'  out H'0005'") for line in lines), lines
        assert any("a0=7.500V" in line for line in lines if line.startswith("TES 2"))
        assert any(f"aout: a0={volts}" in line for line in lines if line.startswith("TES 3"))
    finally:
        plant.close()


def test_fieldtwin_run_prints_the_values_in_its_status_lines(tmp_path: Path) -> None:
    path = tmp_path / "tes.toml"
    path.write_text(PLANT)
    argv = ["run", str(path), "--speed", "max", "--duration", "2", "--no-live"]
    done = subprocess.run(
        [sys.executable, "-m", "fieldtwin", *argv, "--status-every", "1", "--no-control"],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    lines = done.stdout.splitlines()
    assert any(line.startswith("TES 1 TES 32EST: on") and "in H'0009'" in line for line in lines)
    assert any(line.startswith("TES 2 TES 8EA: on") and "a0=7.500V" in line for line in lines)
    assert any(line.startswith("TES 3 TES 4SA: on") and "aout: a0=" in line for line in lines)
