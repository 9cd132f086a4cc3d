"""Helpers for the dashboard tests: open the page, wait in simulated time (bounded)."""

from __future__ import annotations

from typing import Any

from tests.control.plantproc import Running

WALL_MARGIN_MS = 15_000  # on top of the simulated bound at the plant's speed


def open_dashboard(page: Any, plant: Running, rate: int | None = None) -> None:
    url = f"{plant.url}/" + (f"?rate={rate}" if rate else "")
    page.goto(url)
    page.wait_for_function("window.__fieldtwin && window.__fieldtwin.updates > 1")


def sim_time(page: Any) -> float:
    return float(page.evaluate("window.__fieldtwin.state.clock.t_s"))


def wait_sim(page: Any, predicate: str, bound_s: float, speed: float = 4.0) -> float:
    """Wait until the JS ``predicate`` holds, at most ``bound_s`` of simulated time;
    returns the simulated seconds it took (the test asserts it is within the bound)."""
    start = sim_time(page)
    timeout = bound_s / speed * 1000 + WALL_MARGIN_MS
    page.wait_for_function(predicate, timeout=timeout)
    took = sim_time(page) - start
    assert took <= bound_s, f"{predicate}: took {took:.1f} s of simulated time (bound {bound_s})"
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
