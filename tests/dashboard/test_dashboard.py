"""The dashboard in a real headless Chromium, against a real `fieldtwin run` (issue 12).

One plant (the default plant at x4, free ports) serves every test of this file;
each test opens its own page.  Screenshots go to test-artifacts/dashboard/.
"""

from __future__ import annotations

import csv
import io
import json
import urllib.request
from typing import Any

from pymodbus.client import ModbusTcpClient

from tests.control.plantproc import Running
from tests.dashboard.browser import artifact
from tests.dashboard.pages import element_shot, open_controls, open_dashboard, wait_sim

MODULES = {"4": "TSX DEM 2412", "5": "TSX AEM 811", "7": "TSX SCM 2111", "14": "TSX DET 805",
           "16": "TSX DST 1635", "17": "TSX DST 1635"}  # fmt: skip
TES = {"tes1": "TES 32EST", "tes2": "TES 8EA"}


def api(plant: Running, path: str) -> Any:
    with urllib.request.urlopen(f"{plant.url}{path}", timeout=10) as answer:
        return json.load(answer)


def test_page_loads_the_default_plant_with_every_module_and_tes(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    assert page.locator("#plc-model").inner_text() == "TSX 87"
    assert page.locator("#plc-mode").inner_text() == "RUN"
    assert "master task 10 ms" in page.locator("#plc-scan").inner_text()
    for ident, kind in MODULES.items():
        panel = page.locator(f"#mod-{ident}")
        assert kind in panel.inner_text()
        assert panel.locator("[data-led=OK]").count() == 1
    for ident, kind in TES.items():
        panel = page.locator(f"#tes-{ident}")
        assert kind in panel.inner_text()
        for name in ("Pwr", "Run", "Prm", "Wdg"):
            assert panel.locator(f"[data-led={name}]").count() == 1
    assert page.locator("#mod-7 [data-led=ERR]").count() == 0  # SCM 1.2: OK and F only
    # the DST 1635 at 16 shows the output bits the program writes (O16,0..F rows)
    wait_sim(page, "document.querySelectorAll('#mod-16 .bit.on[data-o]').length > 0", 30)
    assert page.locator("#mod-14 [data-i='0'].on").count() == 1  # DET 805 I14,0 (Run/Stop)
    # the TES 8EA shows its analog inputs in volts and in points
    wait_sim(page, "document.querySelector('#tes-tes2 [data-points=a1]') !== null", 10)
    volts = float(page.locator("#tes-tes2 [data-volts=a1]").inner_text())
    points = int(page.locator("#tes-tes2 [data-points=a1]").inner_text())
    assert volts == 2.5 and abs(points - round(2.5 / 10 * 1023)) <= 1  # TES §4.2.4
    page.screenshot(path=str(artifact("dashboard-1280x800.png")))


def test_moving_an_aem_input_changes_the_measurement_and_the_iw_word(
    page: Any, plant: Running
) -> None:
    open_dashboard(page, plant)
    # channel 4: 0/10 V, square root, 0..20000; 2.5 V reads 10000 (IW5,3 multiplexed)
    wait_sim(page, "document.querySelector('#mod-5 [data-meas=\"4\"]').textContent === '10000'", 30)
    box = open_controls(page, "#mod-5")
    row = box.locator(".input-row[data-input='4']")
    row.locator("input.value").fill("6.4V")
    row.locator("button.set").click()
    took = wait_sim(
        page, "document.querySelector('#mod-5 [data-meas=\"4\"]').textContent === '16000'", 5
    )
    wait_sim(
        page, "document.querySelector('#mod-5 [data-w=\"IW5,3\"]').textContent === \"H'3E80'\"", 5
    )
    assert took <= 5
    assert api(plant, "/devices/5/objects/IW5,3")["value"] == 16000
    row.locator("input.value").fill("2.5V")
    row.locator("button.set").click()
    wait_sim(page, "document.querySelector('#mod-5 [data-meas=\"4\"]').textContent === '10000'", 5)


def test_toggling_a_tes_input_shows_in_a_pymodbus_read(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    client = ModbusTcpClient("127.0.0.1", port=plant.modbus_port, timeout=5)
    assert client.connect()
    try:

        def bit3() -> int:
            answer = client.read_holding_registers(5, count=1, device_id=1)  # direct[0]
            assert not answer.isError(), answer
            return int(answer.registers[0] >> 3 & 1)

        before = bit3()
        box = open_controls(page, "#tes-tes1")
        box.locator(".input-row[data-input='3'] button.toggle").click()
        want = str(1 - before)
        page.wait_for_function(
            "(want) => document.querySelector('#tes-tes1 .msg').textContent.endsWith('-> ' + want)",
            arg=want,
        )
        assert bit3() == 1 - before
        wait_sim(
            page,
            "document.querySelector('#tes-tes1 [data-in=\"3\"]').classList.contains('on')"
            f" === {str(not before).lower()}",
            5,
        )
    finally:
        client.close()


def test_a_trend_of_a_changing_value_draws_points_and_exports_csv(
    page: Any, plant: Running
) -> None:
    open_dashboard(page, plant, rate=10)
    # the default plant opens with its four tank levels trended: cleared, this one is alone
    page.wait_for_function("window.__fieldtwinTrends.series.length === 4")
    page.click("#trend-clear")
    page.select_option("#trend-pick", "tes2:a0:V")  # a sine, 5 +- 4 V over 60 s
    page.click("#trend-add")
    page.wait_for_function(
        "window.__fieldtwinTrends.chart && window.__fieldtwinTrends.chart.data[0].length > 30"
    )
    data = page.evaluate("window.__fieldtwinTrends.chart.data")
    values = [v for v in data[1] if v is not None]
    assert len(values) > 30 and len(set(values)) > 5, values  # points, and it changes
    assert page.locator("#trend-chart canvas").count() >= 1
    element_shot(page, "#trends", str(artifact("dashboard-trend.png")))
    with page.expect_download() as download:
        page.click("#trend-csv")
    text = download.value.path().read_text()
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0] == ["t_s", "tes2 a0 V"]
    assert len(rows) > 30
    times = [float(r[0]) for r in rows[1:]]
    assert times == sorted(times)


def test_a_bad_value_gets_a_visible_error_and_changes_nothing(page: Any, plant: Running) -> None:
    open_dashboard(page, plant)
    wait_sim(page, "document.querySelector('#mod-5 [data-meas=\"6\"]').textContent === '16000'", 30)
    before = api(plant, "/dashboard/state")["modules"][1]["decoded"]["channels"][6]["value"]
    box = open_controls(page, "#mod-5")
    row = box.locator(".input-row[data-input='6']")
    row.locator("input.value").fill("abc")
    row.locator("button.set").click()
    error = page.locator("#error")
    error.wait_for(state="visible")
    assert "'abc' not allowed" in error.inner_text()
    assert "not allowed" in box.locator(".msg.bad").inner_text()
    page.wait_for_timeout(1000)  # the page goes on; the plant kept its input
    assert page.locator("#mod-5 [data-meas='6']").inner_text() == "16000"
    channel = api(plant, "/dashboard/state")["modules"][1]["decoded"]["channels"][6]
    assert channel["value"] == 16000 == before  # what the module measures did not move
    # a step that is not a number is refused in the page, before any request
    page.fill("#step-ms", "ten")
    page.click("#step")
    assert "not a number" in error.inner_text()
    assert api(plant, "/clock")["paused"] is False
    page.screenshot(path=str(artifact("dashboard-bad-value.png")))


def test_usable_at_1280x800_and_on_a_390_pixel_phone(page: Any, plant: Running) -> None:
    for width, height in ((1280, 800), (390, 844)):
        page.set_viewport_size({"width": width, "height": height})
        open_dashboard(page, plant)
        overflow = page.evaluate("document.documentElement.scrollWidth")
        assert overflow <= width, f"{width} px: the page is {overflow} px wide"
        for ident in ("4", "5", "7"):
            box = page.locator(f"#mod-{ident}").bounding_box()
            assert box is not None and box["x"] >= 0 and box["x"] + box["width"] <= width + 1
        assert page.locator("#pause").is_visible() and page.locator("#clock").is_visible()
        page.screenshot(path=str(artifact(f"dashboard-{width}.png")))
