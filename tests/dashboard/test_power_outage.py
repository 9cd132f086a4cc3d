"""The dashboard's power cycle with a duration (issue 22 item 4), in a real browser: the
TES box's seconds field turns its power cycle into an outage that lasts."""

from __future__ import annotations

import json
import urllib.request
from typing import Any

from tests.control.plantproc import Running
from tests.dashboard.pages import open_controls, open_dashboard


def leds(running: Running, device: str) -> dict[str, str]:
    with urllib.request.urlopen(f"{running.url}/devices/{device}/leds", timeout=10) as answer:
        found: dict[str, str] = json.load(answer)
    return found


def test_the_power_cycle_button_takes_seconds(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    box = open_controls(page, "#tes-tes2")
    box.locator("input.outage").fill("20")  # simulated seconds (x4: 5 s of wall time)
    box.locator("button.power-cycle").click()
    page.wait_for_function(
        "document.querySelector('#tes-tes2 .msg').textContent === 'power off for 20 s'"
    )
    assert leds(plant, "tes2")["Pwr"] == "off"
    box.locator("input.outage").fill("4000")
    box.locator("button.power-cycle").click()
    page.locator("#error").wait_for(state="visible")
    assert "0 to 3600" in page.locator("#error").inner_text()
