"""The made-up device on the dashboard: its fault with a parameter (offered where its
loop is, with its hint, lit when set with curl) and its output in volts, from a real
`fieldtwin run` that imports tests/devices/madeup.py first (no edit outside it)."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from typing import Any

import pytest

from tests.control.plantproc import ROOT, Running, fieldtwin_run_with
from tests.dashboard.pages import curl, open_controls, open_dashboard
from tests.devices.madeup import LEVEL

RUN = "import sys, tests.devices.madeup; from fieldtwin.cli import main; sys.exit(main())"
PLANT = f"""
[plc]
model = "TSX 87"

[[module]]
type = "{LEVEL}"
slot = 3
loop = "4-20"
inputs = {{ "0" = 2.0 }}
"""


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    path = tmp_path_factory.mktemp("madeup") / "plant.toml"
    path.write_text(PLANT)
    with fieldtwin_run_with([sys.executable, "-c", RUN], path, ROOT, None) as running:
        yield running


def test_the_made_up_device_on_the_dashboard(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    box = open_controls(page, "#mod-3")
    assert box.locator("button.fault").evaluate_all("bs => bs.map(b => b.dataset.fault)") == [
        "float_stuck",
        "noise",
    ]
    hint = box.locator("button.fault[data-fault=noise] + input.args")
    assert hint.get_attribute("placeholder") == "mv=1"
    curl(plant, "PUT", "/devices/3/faults/noise", {"params": {"mv": 50}})
    button = "#mod-3 button.fault[data-fault=noise]"
    page.wait_for_function(f"document.querySelector('{button}').classList.contains('active')")
    assert "noise mv=50" in page.locator("#mod-3 [data-f=faults]").inner_text()
    curl(plant, "PUT", "/devices/3/objects/OW3,0", {"value": 4500})
    page.wait_for_function(
        "document.querySelector('#mod-3 [data-aout=\"0\"]').textContent === '4.500 V'"
    )


def test_its_front_is_drawn_from_its_typed_panel(page: Any, plant: Running) -> None:
    # no layout of its own: the page draws its Device.panel() (reading, unit, flags, fields)
    open_dashboard(page, plant)
    reading = "#mod-3 [data-reading=level]"
    page.wait_for_function(
        f"/^2\\.0[0-9]0 V$/.test(document.querySelector('{reading}')?.textContent)"
    )
    assert page.locator("#mod-3 [data-field=loop]").inner_text() == "4-20"
    curl(plant, "PUT", "/devices/3/faults/float_stuck", {"active": True})
    flags = "#mod-3 [data-flags=level]"
    page.wait_for_function(f"document.querySelector('{flags}').textContent === 'float_stuck'")
    curl(plant, "PUT", "/devices/3/faults/float_stuck", {"active": False})
    page.wait_for_function(f"document.querySelector('{flags}').textContent === ''")
