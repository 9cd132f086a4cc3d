"""The dashboard's views (issue 22, item 5), on a real `fieldtwin run` of the default
plant: a removed module without its measurement table, Text Block reports in H'..' with
the data as text, each TES's last request and its outcome (the traffic list too),
writing a TES register and a PL7 object from the page, and a plant that stopped shown
as stopped (no green RUN, no lit LED, a banner)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from pymodbus.client import ModbusTcpClient
from pymodbus.exceptions import ModbusException

from tests.control.plantproc import Running, default_plant_copy, fieldtwin_run
from tests.dashboard.browser import artifact
from tests.dashboard.pages import curl, open_controls, open_dashboard, wait_sim


def test_a_removed_module_shows_no_measurement_table(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    page.wait_for_function("document.querySelectorAll('#mod-5 [data-meas]').length === 8")
    curl(plant, "POST", "/plc/remove", {"module": "5"})
    try:
        wait_sim(page, "document.querySelector('#mod-5 [data-f=removed]') !== null", 5)
        display = page.locator("#mod-5 .display")
        assert display.locator("[data-meas]").count() == 0
        assert display.locator("table").count() == 0  # no words, no measurements
        assert page.locator("#mod-5 [data-f=state]").inner_text() == "removed"
        lit = display.locator(".led.led-on, .led.led-blink").count()
        assert lit == 0
        assert "insert module" in display.inner_text()
    finally:
        curl(plant, "POST", "/plc/insert", {"module": "5"})
    wait_sim(page, "document.querySelectorAll('#mod-5 [data-meas]').length === 8", 5)


def run_exchange(page: Any, c: str) -> None:
    form = page.locator("#txt-form")
    form.locator("input[name=c]").fill(c)
    page.eval_on_selector("#txt-result [data-f=state]", "e => { e.textContent = '' }")
    page.locator("#txt-run").click()
    page.wait_for_function(
        "document.querySelector('#txt-result [data-f=state]').textContent === 'done'",
        timeout=30_000,
    )


def cell(page: Any, field: str) -> str:
    return str(page.locator(f"#txt-result [data-f={field}]").inner_text())


def test_text_block_reports_in_hex_and_the_data_as_text(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    # the AEM's name (C = H'4A', AEM 4.4): 20 characters, report H'7A'
    run_exchange(page, "H'4A'")
    assert cell(page, "V") == "H'7A' (122)"
    assert cell(page, "error") == "-"
    data = cell(page, "data").split()
    assert len(data) == 20 and set(data) == {"20"}
    assert page.locator("#txt-result [data-f=text]").text_content() == '"' + " " * 20 + '"'
    # the fault bits (C = H'47'): report H'77', eight bytes of zero are no text
    run_exchange(page, "H'47'")
    assert cell(page, "V") == "H'77' (119)"
    assert cell(page, "data") == "00 00 00 00 00 00 00 00"
    assert cell(page, "text") == "-"
    assert cell(page, "words").startswith("H'0000' H'0000'")


def test_each_tes_shows_its_last_request_and_outcome(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    outcome = "#tes-tes2 [data-f=outcome]"
    client = ModbusTcpClient("127.0.0.1", port=plant.modbus_port, timeout=2, retries=0)
    assert client.connect()
    try:
        curl(plant, "PUT", "/devices/tes2/faults/late_answer", {"params": {"ms": 200}})
        assert not client.read_holding_registers(0, count=2, device_id=2).isError()
        late = f"document.querySelector('{outcome}')?.textContent === 'answers after 200 ms'"
        # the reply's event may come in a later batch than the request's: wait for both
        replied = "document.querySelector('#tes-tes2 [data-f=last-request]')"
        wait_sim(page, f"{late} && ({replied}?.textContent || '').includes('answered')", 5)
        shown = page.locator("#tes-tes2 [data-f=last-request]").inner_text()
        assert "read_holding_registers @0 x2" in shown and "answered" in shown
        curl(plant, "PUT", "/devices/tes2/faults/late_answer", {"active": False})
        curl(plant, "PUT", "/devices/tes2/faults/no_answer", {"active": True})
        with pytest.raises(ModbusException):  # a timeout: the TES does not answer
            client.read_holding_registers(1, count=1, device_id=2)
        wait_sim(page, f"document.querySelector('{outcome}')?.textContent === 'no_answer'", 5)
        assert "alarm" in (page.locator(outcome).get_attribute("class") or "")
        # the traffic list says it too, beside the frame
        page.wait_for_function(
            "[...document.querySelectorAll('#traffic-table td')]"
            ".some((td) => td.textContent.includes('→ TES 8EA #2 no_answer'))"
        )
    finally:
        client.close()
        curl(plant, "PUT", "/devices/tes2/faults/no_answer", {"active": False})
    # the other TES of the endpoint was not addressed: its own line says so, unchanged
    assert "no_answer" not in page.locator("#tes-tes1 .display").inner_text()


def test_a_tes_register_and_a_pl7_object_are_written_from_the_page(
    page: Any, plant: Running
) -> None:
    open_dashboard(page, plant)
    box = open_controls(page, "#tes-tes1")
    row = box.locator(".write-row")
    row.locator(".obj-name").fill("H'00A'")  # filter_0 of the TES 32EST, a parameter word
    row.locator(".obj-value").fill("H'0004'")
    row.locator("button.write").click()
    msg = page.locator("#tes-tes1 .msg")
    page.wait_for_function("document.querySelector('#tes-tes1 .msg').textContent !== ''")
    assert msg.inner_text() == "H'00A' written"
    page.wait_for_function("document.querySelector('#tes-tes1 .obj-read').textContent !== ''")
    assert row.locator(".obj-read").inner_text() == "H'00A' = H'0004'"
    assert curl(plant, "GET", "/devices/tes1/objects/filter_0?peek=true")["value"] == 4
    # a PL7 object of the DEM (OW4,3: channels 16..23 logged), written at the module
    dem = open_controls(page, "#mod-4").locator(".write-row")
    dem.locator(".obj-name").fill("OW4,3")
    dem.locator(".obj-value").fill("0x00F0")
    dem.locator("button.write").click()
    page.wait_for_function("document.querySelector('#mod-4 .obj-read').textContent !== ''")
    assert dem.locator(".obj-read").inner_text() == "OW4,3 = H'00F0'"
    assert curl(plant, "GET", "/devices/4/objects/OW4,3?peek=true")["value"] == 0xF0
    # a value the page can tell is no number is refused before anything is sent ...
    dem.locator(".obj-value").fill("ten")
    dem.locator("button.write").click()
    msg = page.locator("#mod-4 .msg")
    page.wait_for_function("document.querySelector('#mod-4 .msg').textContent.includes('ten')")
    assert "is not a value 0..65535" in msg.inner_text()
    # ... and an object the module has not gets the module's own answer
    dem.locator(".obj-name").fill("W0")
    dem.locator(".obj-value").fill("1")
    dem.locator("button.write").click()
    page.wait_for_function("document.querySelector('#mod-4 .msg').textContent.includes('W0')")
    assert "unknown object" in msg.inner_text()
    curl(plant, "PUT", "/devices/4/objects/OW4,3", {"value": 0})


def test_a_stopped_plant_shows_as_stopped(browser: Any, tmp_path: Path) -> None:
    context = browser.new_context(viewport={"width": 1280, "height": 800})
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.set_default_timeout(20_000)
    try:
        with fieldtwin_run(default_plant_copy(tmp_path), "--speed", "4") as running:
            open_dashboard(page, running)
            page.wait_for_function("document.querySelector('#plc-mode').textContent === 'RUN'")
            page.wait_for_function("document.querySelectorAll('main .led.led-on').length > 3")
            green = page.eval_on_selector("#plc-mode", "e => getComputedStyle(e).backgroundColor")
            assert page.locator("#plant-down").is_hidden()
            running.proc.terminate()
            running.proc.wait(timeout=15)
            page.wait_for_function("document.body.classList.contains('plant-down')")
        banner = page.locator("#plant-down")
        assert banner.is_visible()
        assert "The plant does not answer" in banner.inner_text()
        assert "last seen, at t = " in banner.inner_text()
        assert page.locator("#plc-mode").inner_text() == "no answer"
        badge = page.eval_on_selector("#plc-mode", "e => getComputedStyle(e).backgroundColor")
        assert badge != green
        lit = page.eval_on_selector_all(
            "main .led",
            "ls => ls.filter((l) => getComputedStyle(l).boxShadow !== 'none').length",
        )
        assert lit == 0
        grey = page.eval_on_selector("main .panel", "e => getComputedStyle(e).filter")
        assert "grayscale" in grey
        page.screenshot(path=str(artifact("dashboard-stopped.png")))
    finally:
        context.close()
    assert not errors, f"the page raised: {errors}"
