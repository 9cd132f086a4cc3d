"""The dashboard's other controls in a real browser: the clock, a signal preset, the
Text Block panel, and the traffic view with its filters (issue 12, items 3 and 5)."""

from __future__ import annotations

import json
import urllib.request
from typing import Any

from pymodbus.client import ModbusTcpClient

from tests.control.plantproc import Running
from tests.dashboard.browser import artifact
from tests.dashboard.pages import element_shot, open_controls, open_dashboard, wait_sim


def api(plant: Running, path: str) -> Any:
    with urllib.request.urlopen(f"{plant.url}{path}", timeout=10) as answer:
        return json.load(answer)


def test_clock_pause_step_speed_and_resume(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    page.click("#pause")
    page.wait_for_function("document.querySelector('#clock').textContent.includes('paused')")
    before = api(plant, "/clock")
    assert before["paused"] is True
    page.fill("#step-ms", "250")
    page.click("#step")
    page.wait_for_function(
        "(t) => window.__fieldtwin.state.clock.t_us >= t", arg=before["t_us"] + 250_000
    )
    after = api(plant, "/clock")
    assert after["t_us"] - before["t_us"] == 250_000 and after["paused"] is True
    page.fill("#speed-value", "2")
    page.click("#set-speed")
    page.wait_for_function("document.querySelector('#speed').textContent === 'speed x2'")
    page.fill("#speed-value", "4")
    page.click("#set-speed")
    page.click("#resume")
    page.wait_for_function("!document.querySelector('#clock').textContent.includes('paused')")
    clock = {k: v for k, v in api(plant, "/clock").items() if k in ("paused", "speed")}
    assert clock | {"t_s": 0, "t_us": 0} == {
        "t_s": 0, "t_us": 0, "paused": False, "speed": 4.0,
    }  # fmt: skip


def test_a_signal_preset_drives_a_tes_analog_input(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    box = open_controls(page, "#tes-tes2")
    row = box.locator(".input-row[data-input='a1']")
    row.locator("select.preset").select_option("ramp")
    row.locator("input.args").fill("start=1 end=9 t0_s=0 duration_s=1")
    row.locator("button.drive").click()
    page.wait_for_function(
        "document.querySelector('#tes-tes2 .msg').textContent === 'input a1: ramp'"
    )
    wait_sim(page, "document.querySelector('#tes-tes2 [data-volts=a1]').textContent === '9.000'", 5)
    row.locator("select.preset").select_option("sine")
    row.locator("input.args").fill("offset=5 amplitude=oops")
    row.locator("button.drive").click()
    page.locator("#error").wait_for(state="visible")
    assert "amplitude" in page.locator("#error").inner_text()
    assert page.locator("#tes-tes2 [data-volts=a1]").inner_text() == "9.000"  # unchanged
    row.locator("input.value").fill("2.5")
    row.locator("button.set").click()
    wait_sim(page, "document.querySelector('#tes-tes2 [data-volts=a1]').textContent === '2.500'", 5)


def test_the_text_block_panel_runs_an_exchange(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    wait_sim(page, "window.__fieldtwin.state.modules.find(m => m.id === '5').mode === 'Run'", 30)
    form = page.locator("#txt-form")
    form.locator("input[name=m]").fill("zz")
    form.locator("button[type=submit]").click()
    assert "m = zz is not a number" in page.locator("#error").inner_text()
    form.locator("input[name=m]").fill("H'0563'")  # AEM 4.4: read the status words
    form.locator("input[name=c]").fill("H'4A'")
    form.locator("input[name=recv]").fill("20")
    form.locator("input[name=txt]").fill("7")
    form.locator("button[type=submit]").click()
    result = page.locator("#txt-result")
    page.wait_for_function(
        "document.querySelector('#txt-result [data-f=state]').textContent !== '-'"
    )
    page.wait_for_function(
        "['-', 'running', 'busy', 'started'].indexOf("
        "document.querySelector('#txt-result [data-f=E]').textContent) < 0",
        timeout=30_000,
    )
    assert result.locator("[data-f=E]").inner_text() == "0"
    assert result.locator("[data-f=V]").inner_text() != "-"
    assert result.locator("[data-f=words]").inner_text() != "-"
    element_shot(page, "#textblock", str(artifact("dashboard-textblock.png")))


def test_the_traffic_view_filters_by_endpoint_slave_and_function(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    page.wait_for_timeout(500)  # the event stream is open
    client = ModbusTcpClient("127.0.0.1", port=plant.modbus_port, timeout=5)
    assert client.connect()
    try:
        for _ in range(3):
            assert not client.read_holding_registers(0, count=2, device_id=1).isError()
            assert not client.read_holding_registers(3, count=2, device_id=2).isError()
    finally:
        client.close()
    page.select_option("#f-kind", "modbus")
    page.fill("#f-function", "3")
    for slave in ("2", "1"):
        page.fill("#f-slave", slave)
        page.wait_for_function(
            "(slave) => { const rows = [...document.querySelectorAll('#traffic-table tbody tr')];"
            " return rows.length >= 6"
            " && rows.every(r => r.children[2].textContent.endsWith(' ' + slave)); }",
            arg=slave,
        )
        rows = page.locator("#traffic-table tbody tr").all_inner_texts()
        assert all("modbus" in r and "read_holding_registers" in r for r in rows), rows
    page.fill("#f-function", "16")
    page.wait_for_function("document.querySelectorAll('#traffic-table tbody tr').length === 0")
    page.fill("#f-function", "3")
    page.fill("#f-endpoint", "udp://nowhere")
    page.wait_for_function("document.querySelectorAll('#traffic-table tbody tr').length === 0")
    page.fill("#f-endpoint", "tcp://127.0.0.1")
    page.wait_for_function("document.querySelectorAll('#traffic-table tbody tr').length >= 6")
    element_shot(page, "#traffic", str(artifact("dashboard-traffic.png")))
