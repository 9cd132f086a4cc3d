"""The terminal live view shows the output bits of the discrete modules (O16,0..F)
at every width, and still fits 80 columns."""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from rich.console import Console as RichConsole

from fieldtwin.live import output_bits, render
from fieldtwin.plant import load_plant
from tests.cli.test_cli import default_plant_copy


@pytest.mark.parametrize("width", [80, 110, 160])
def test_the_dst_output_bits_show_at_every_width(tmp_path: Path, width: int) -> None:
    plant = load_plant(default_plant_copy(tmp_path), speed=None)
    plc = plant.plc
    assert plc is not None
    plc.advance(40.0)
    lamps = output_bits(plc, 1, 6)
    assert lamps != 0  # the program lights threshold lamps on the DST at 16
    assert lamps == sum(plc.read(f"O16,{b:X}") << b for b in range(16))
    screen = RichConsole(record=True, width=width, file=io.StringIO(), color_system=None)
    screen.print(render(plant, []))
    lines = screen.export_text().splitlines()
    assert all(len(line) <= width for line in lines)
    text = "\n".join(lines)
    shown = f"{lamps:016b}" if width >= 150 else f"{lamps:04X}"
    row = next(i for i, line in enumerate(lines) if " TSX DST 1635 " in line and " 16 " in line)
    if width < 104:  # under the I word, on the row's second line
        assert shown in lines[row + 1], text
        assert "I / O" in text
    else:
        assert shown in lines[row], text
    plant.close()
