"""A TES 4SA's analog output on the dashboard in volts, the word beside, from a real
`fieldtwin run` whose output a master's write moves (issue 21, "Done means")."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.control.plantproc import Running, fieldtwin_run
from tests.dashboard.pages import curl, open_dashboard

PLANT = """
[[tes]]
model = "TES 4SA"
endpoint = "tcp://127.0.0.1:0"
slave = 2
"""


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    path: Path = tmp_path_factory.mktemp("tes4sa") / "plant.toml"
    path.write_text(PLANT)
    with fieldtwin_run(path) as running:
        yield running


def test_a_tes_4sa_analog_output_shows_in_volts(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    curl(plant, "PUT", "/devices/tes2/objects/H'014'", {"value": 0x4000})
    a0 = next(o for o in curl(plant, "GET", "/devices/tes2/outputs") if o["name"] == "a0")
    assert a0["unit"] == "V" and a0["raw"] == 0x4000
    shown = f"{a0['value']:.3f} V"
    cell = "#tes-tes2 [data-aout=a0]"
    page.wait_for_function(f"document.querySelector('{cell}')?.textContent === '{shown}'")
    row = page.locator(cell).locator("xpath=..").inner_text()
    assert "H'4000'" in row
