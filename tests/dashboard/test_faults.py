"""A fault button lights the module's F LED and sets I,S; the control API agrees.

Its own plant: the AEM's processor fault is blocking until a power-up (AEM 7.1),
and a power break from the page brings the module back.
"""

from __future__ import annotations

import json
import urllib.request
from typing import Any

from tests.control.plantproc import Running
from tests.dashboard.browser import artifact
from tests.dashboard.pages import element_shot, open_controls, open_dashboard, wait_sim


def api(plant: Running, path: str) -> Any:
    with urllib.request.urlopen(f"{plant.url}{path}", timeout=10) as answer:
        return json.load(answer)


def test_a_fault_button_lights_f_and_sets_i_s(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    wait_sim(
        page, "document.querySelector('#mod-5 [data-led=OK]').classList.contains('led-on')", 30
    )
    assert "led-off" in (page.locator("#mod-5 [data-led=F]").get_attribute("class") or "")
    assert page.locator("#mod-5 [data-f=is]").inner_text() == "0"
    box = open_controls(page, "#mod-5")
    box.locator("button.fault[data-fault=processor]").click()
    wait_sim(page, "document.querySelector('#mod-5 [data-led=F]').classList.contains('led-on')", 2)
    wait_sim(page, "document.querySelector('#mod-5 [data-f=is]').textContent === '1'", 2)
    assert "active" in (
        box.locator("button.fault[data-fault=processor]").get_attribute("class") or ""
    )
    assert api(plant, "/devices/5/leds")["F"] == "on"
    assert api(plant, "/devices/5/objects/I5,S")["value"] == 1
    element_shot(page, "#mod-5", str(artifact("dashboard-aem-fault.png")))
    # the power break and return, from the header: the module restarts its self-test
    page.fill("#break-s", "0.5")
    page.click("#power-break")
    wait_sim(page, "document.querySelector('#mod-5 [data-led=F]').classList.contains('led-off')", 5)
    assert api(plant, "/devices/5/leds")["F"] == "off"


def test_module_removal_and_a_tes_line_fault_from_the_page(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    box = open_controls(page, "#mod-7")
    box.locator("button.remove").click()
    wait_sim(
        page, "document.querySelector('#mod-7 [data-f=state]').textContent.startsWith('removed')", 2
    )
    box.locator("button.insert").click()
    wait_sim(
        page,
        "!document.querySelector('#mod-7 [data-f=state]').textContent.startsWith('removed')",
        2,
    )
    tes = open_controls(page, "#tes-tes1")
    tes.locator("button.fault[data-fault=late_answer] + input.args").fill("ms=abc")
    tes.locator("button.fault[data-fault=late_answer]").click()
    assert "abc" in page.locator("#error").inner_text()  # refused in the page: nothing sent
    tes.locator("button.fault[data-fault=late_answer] + input.args").fill("ms=200")
    tes.locator("button.fault[data-fault=late_answer]").click()
    page.wait_for_function(
        "document.querySelector('#tes-tes1 .msg').textContent === 'late_answer set'"
    )
    tes.locator("button.fault[data-fault=late_answer]").click()
    page.wait_for_function(
        "document.querySelector('#tes-tes1 .msg').textContent === 'late_answer cleared'"
    )
