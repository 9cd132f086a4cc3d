"""Tags on the dashboard of a real `fieldtwin run`: labels and values in their units, and
a trend of a tagged AEM channel in engineering units with the history kept before the
page opened (issue 22, "Done means")."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.control.plantproc import ROOT, Running, fieldtwin_run
from tests.dashboard.pages import open_dashboard

TAGS = """
[dashboard]
trends = ["tank.level"]

[[tag]]
name = "tank.level"
device = "5"
input = "0"
unit = "m"
scale = [0, 10000, 0, 10]
description = "tank 0 level, the AEM's channel 0 (4..20 mA = 0..10000 mm)"

[[tag]]
name = "run.switch"
object = "I14,0"
description = "the Run/Stop switch"
"""


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    path: Path = tmp_path_factory.mktemp("tags") / "plant.toml"
    example = (ROOT / "examples" / "aem811_tank.toml").read_text()
    example = example.split("\n[dashboard]\n", 1)[0]  # its racks, not its own tags
    path.write_text("[run]\nspeed = 4\n" + example + TAGS)
    with fieldtwin_run(path) as running:
        yield running


def test_the_page_shows_tags_with_units_and_trends_a_tagged_channel(
    page: Any, plant: Running
) -> None:
    open_dashboard(page, plant)
    opened_at = float(page.evaluate("window.__fieldtwin.state.clock.t_s"))
    # the AEM's channel 0 at 12 mA, once configured: 5000 mm (5001), shown as 5 m
    cell = "#tag-table [data-tag-value='tank.level']"
    page.wait_for_function(
        f"/^5(\\.\\d+)? m$/.test(document.querySelector(\"{cell}\")?.textContent || '')"
    )
    row = page.locator("#tag-table tr[data-tag='tank.level']").inner_text()
    assert "5 input 0" in row and "tank 0 level" in row
    assert page.locator("#tag-table [data-tag-value='run.switch']").inner_text() == "on"
    # beside the fronts: the AEM's and the DET's own tags
    assert "tank.level" in page.locator("#mod-5 [data-tag-note='tank.level']").inner_text()
    assert "run.switch" in page.locator("#mod-14 [data-tag-note='run.switch']").inner_text()
    # the plant file's default trend: the tagged channel, in metres, from before the page
    page.wait_for_function(
        "window.__fieldtwinTrends.series.length === 1"
        " && window.__fieldtwinTrends.data()[1].some((v) => v !== null && Math.abs(v - 5) < 0.01)"
    )
    label = page.evaluate("window.__fieldtwinTrends.series[0].label")
    assert label == "tank.level (m)"
    times, values = page.evaluate("window.__fieldtwinTrends.data()")
    assert times[0] < opened_at  # history the plant kept before the page opened
    measured = [v for v in values if v is not None]
    assert measured and all(0 <= v <= 10 for v in measured)  # metres, not raw counts
    picked = page.evaluate("[...document.querySelectorAll('#trend-pick option')].map(o => o.text)")
    assert "tank.level (m)" in picked and "run.switch" in picked
