"""A fault set with curl shows on the page without a reload; only the faults that apply
are offered, each with the parameter hint of what it takes (issue 21)."""

from __future__ import annotations

from typing import Any

from tests.control.plantproc import Running
from tests.dashboard.pages import curl, open_controls, open_dashboard, wait_sim

BUTTON = "#tes-tes1 button.fault[data-fault=late_answer]"


def test_a_fault_set_with_curl_lights_its_button_without_a_reload(
    page: Any, plant: Running
) -> None:
    open_dashboard(page, plant)
    box = open_controls(page, "#tes-tes1")
    assert "active" not in (page.locator(BUTTON).get_attribute("class") or "")
    curl(plant, "PUT", "/devices/tes1/faults/late_answer", {"params": {"ms": 200}})
    wait_sim(page, f"document.querySelector('{BUTTON}').classList.contains('active')", 10)
    assert "late_answer ms=200" in page.locator("#tes-tes1 [data-f=faults]").inner_text()
    # the page's click now clears it (it does not set it a second time)
    page.locator(BUTTON).click()
    page.wait_for_function(
        "document.querySelector('#tes-tes1 .msg').textContent === 'late_answer cleared'"
    )
    assert curl(plant, "GET", "/devices/tes1")["active_faults"] == {}
    wait_sim(page, f"!document.querySelector('{BUTTON}').classList.contains('active')", 10)
    # the click's own answer turns the button off at once; the note goes with the next poll
    wait_sim(page, "!document.querySelector('#tes-tes1 [data-f=faults]')", 10)
    assert page.locator("#tes-tes1 [data-f=faults]").count() == 0
    # only the faults that apply to a TES on Modbus TCP, each with its own hint
    offered = box.locator("button.fault").evaluate_all("bs => bs.map(b => b.dataset.fault)")
    assert "bad_crc" not in offered and "broken_character" not in offered
    assert "drop_connections" in offered
    hint = box.locator("button.fault[data-fault=not_ready] + input.args")
    assert hint.get_attribute("placeholder") == "count=3 window_ms=20"
    late = box.locator("button.fault[data-fault=late_answer] + input.args")
    assert late.get_attribute("placeholder") == "ms=200"
    assert box.locator("button.fault[data-fault=no_answer] + input.args").count() == 0
