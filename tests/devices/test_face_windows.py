"""The console's status and the live view render a device's typed front panel
(Device.panel()), and no window branches on a family's address class (issue 21)."""

from __future__ import annotations

import io
import re
from pathlib import Path

from rich.console import Console as RichConsole

import tests.devices.madeup  # noqa: F401  its registry line
from fieldtwin.console import Console
from fieldtwin.devices.face import FrontPanel, PanelWord, Reading, reading_text
from fieldtwin.live import render
from fieldtwin.plant import load_plant
from tests.cli.test_cli import default_plant_copy
from tests.devices.madeup import LEVEL

SRC = Path(__file__).resolve().parents[2] / "src" / "fieldtwin"
WINDOWS = ("live.py", "console.py", "control/panels.py")


def test_no_window_names_a_family_address() -> None:
    for name in WINDOWS:
        text = (SRC / name).read_text()
        assert not re.search(r"\b(TesAddress|ModuleAddress)\b", text), name


def test_the_front_as_text() -> None:
    panel = FrontPanel(
        (("OK", "on"),),
        words=(PanelWord("watchdog", 0x1E), PanelWord("lost", None)),
        readings=(
            Reading("0", 2.5, "V"),
            Reading("1", None, flags=("inhibited",)),
            Reading("2", 11, "", ("overflow",)),
        ),
        frozen=(Reading("3", 12, "rises"),),
    )
    assert panel.lines() == [
        "watchdog: H'001E'",
        "lost: -",
        "readings: 0=2.500V 1=- [inhibited] 2=11 [overflow]",
        "frozen: 3=12 rises",
    ]
    assert reading_text(Reading("a0", 12.0, "mA")) == "a0=12.000mA"


def test_console_status_renders_the_typed_front_of_a_tes_and_a_module(tmp_path: Path) -> None:
    plant = load_plant(default_plant_copy(tmp_path), speed=None)
    console = Console(plant)
    console.execute("advance 3")
    console.execute("tes 2 input a1 3V")
    status = console.execute("tes 2 status")
    assert status[0].startswith("TES 2 TES 8EA: on  status H'")
    assert "in: 0000 (3..0)" in status
    assert any(line.startswith("readings: a0=") and " a1=3.000V" in line for line in status)
    assert console.execute("status tes2") == status  # a device by its id in the control API
    assert console.execute("faults tes1") == console.execute("tes 1 faults")
    module = console.execute("status 5")
    assert any(line.startswith("readings: 0=") for line in module)
    plant.close()


def test_a_made_up_device_front_in_the_console_and_the_live_view(tmp_path: Path) -> None:
    path = tmp_path / "plant.toml"
    path.write_text(
        f'[plc]\nmodel = "TSX 87"\n\n[[module]]\ntype = "{LEVEL}"\nslot = 3\n'
        'inputs = { "0" = 2.0 }\nloop = "4-20"\n'
    )
    plant = load_plant(path)
    console = Console(plant)
    console.execute("advance 1.5")
    assert "readings: level=2.000V" in console.execute("status 3")
    console.execute("fault 3 float_stuck on")
    assert "readings: level=2.000V [float_stuck]" in console.execute("status 3")
    screen = RichConsole(record=True, width=160, file=io.StringIO(), color_system=None)
    screen.print(render(plant, []))
    assert "slot 3 front:  readings: level=2.000V [float_stuck]" in screen.export_text()
    narrow = RichConsole(record=True, width=80, file=io.StringIO(), color_system=None)
    narrow.print(render(plant, []))
    assert "front:" not in narrow.export_text()  # 80 columns keep their layout
    plant.close()
