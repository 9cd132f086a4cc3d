"""The page keeps up with 20 updates per second for 30 s without its memory growing.

A wall-clock black-box test, bounded: 30 s of the page driven at its highest rate
(``?rate=20``), a trend drawing and the traffic view listening; the JS heap is
measured through the Chrome DevTools Protocol after a garbage collection.
"""

from __future__ import annotations

import time
from typing import Any

from tests.control.plantproc import Running
from tests.dashboard.browser import artifact
from tests.dashboard.pages import open_dashboard

RATE = 20
SECONDS = 30.0
WARMUP_S = 5.0


def heap(cdp: Any) -> float:
    cdp.send("HeapProfiler.collectGarbage")
    metrics = {m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]}
    return float(metrics["JSHeapUsedSize"])


def test_twenty_updates_per_second_for_30_s_without_memory_growth(
    page: Any, plant: Running
) -> None:
    cdp = page.context.new_cdp_session(page)
    cdp.send("Performance.enable")
    open_dashboard(page, plant, rate=RATE)
    page.select_option("#trend-pick", "5:IW5,3")
    page.click("#trend-add")
    page.select_option("#trend-pick", "tes2:a0:points")
    page.click("#trend-add")
    page.wait_for_timeout(WARMUP_S * 1000)  # the page's first panels and caches settle
    start_heap = heap(cdp)
    start_updates = page.evaluate("window.__fieldtwin.updates")
    started = time.monotonic()
    page.wait_for_timeout(SECONDS * 1000)
    elapsed = time.monotonic() - started
    updates = page.evaluate("window.__fieldtwin.updates") - start_updates
    end_heap = heap(cdp)
    page.screenshot(path=str(artifact("dashboard-after-30s.png")))
    print(
        f"{updates} updates in {elapsed:.1f} s ({updates / elapsed:.1f}/s);"
        f" JS heap {start_heap / 1e6:.2f} MB -> {end_heap / 1e6:.2f} MB"
    )
    assert updates >= 0.8 * RATE * elapsed, f"{updates} updates in {elapsed:.1f} s"
    grown = end_heap - start_heap
    assert grown < max(2e6, 0.25 * start_heap), (start_heap, end_heap)
    assert page.evaluate("window.__fieldtwinTrends.times.length") >= updates * 0.9
