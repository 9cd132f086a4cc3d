"""Helpers for the dashboard tests: open the page, wait in simulated time (bounded),
call the plant's API as curl would."""

from __future__ import annotations

import json
import urllib.request
from typing import Any

from tests.control.plantproc import Running

WALL_MARGIN_MS = 15_000  # on top of the simulated bound at the plant's speed


def curl(plant: Running, method: str, path: str, body: object | None = None) -> Any:
    """One JSON request to the plant's API (bounded wait), its JSON answer."""
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(
        f"{plant.url}{path}", data=data, method=method, headers={"content-type": "application/json"}
    )
    with urllib.request.urlopen(request, timeout=10) as answer:
        return json.load(answer)


def open_dashboard(page: Any, plant: Running, rate: int | None = None) -> None:
    url = f"{plant.url}/" + (f"?rate={rate}" if rate else "")
    page.goto(url)
    page.wait_for_function("window.__fieldtwin && window.__fieldtwin.updates > 1")


def sim_time(page: Any) -> float:
    return float(page.evaluate("window.__fieldtwin.state.clock.t_s"))


def clock_now(page: Any) -> float:
    """The plant's simulated time now, asked of the API (the page's own copy is up to one
    snapshot old)."""
    return float(page.evaluate("fetch('/clock').then((r) => r.json()).then((c) => c.t_s)"))


def wait_sim(page: Any, predicate: str, bound_s: float, speed: float = 4.0) -> float:
    """Wait until the JS ``predicate`` holds, at most ``bound_s`` of simulated time;
    returns the simulated seconds it took (the test asserts it is within the bound).

    The start is the plant's clock asked of the API; the end is the time of the snapshot
    the page drew the change from, which comes at most one snapshot period (at the page's
    rate and the plant's speed) after the change itself: that period is the page's
    resolution and is allowed on top of the bound."""
    start = clock_now(page)
    timeout = bound_s / speed * 1000 + WALL_MARGIN_MS
    page.wait_for_function(predicate, timeout=timeout)
    took = sim_time(page) - start
    resolution = speed / float(page.evaluate("window.__fieldtwin.rate"))
    assert took <= bound_s + resolution, (
        f"{predicate}: took {took:.1f} s of simulated time (bound {bound_s}"
        f" + {resolution:.2f} s of the page's resolution)"
    )
    return took


def open_controls(page: Any, panel: str) -> Any:
    box = page.locator(f"{panel} details.ctl")
    if box.get_attribute("open") is None:
        box.locator("summary").click()
    return box


def element_shot(page: Any, selector: str, path: str) -> None:
    """A screenshot of one part of the page, the sticky header kept out of it."""
    page.add_style_tag(content="header { position: static !important; }")
    page.locator(selector).screenshot(path=path)
