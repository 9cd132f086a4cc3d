"""Fixtures: one real `fieldtwin run` of the default plant, one headless Chromium."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.control.plantproc import Running, default_plant_copy, fieldtwin_run
from tests.systools import require

SPEED = "4"  # the AEM's 10 s self-test in 2.5 s of wall time; the page polls as at x1


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    tmp: Path = tmp_path_factory.mktemp("dashboard")
    with fieldtwin_run(default_plant_copy(tmp), "--speed", SPEED) as running:
        assert any(line.startswith("dashboard: http://") for line in running.lines), running.lines
        assert running.modbus_port > 0
        yield running


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    path = require("chromium")  # skipped with one summary line when missing (not in CI)
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail(
            "playwright is not installed: `pip install -e '.[dev]'` (make setup)", pytrace=False
        )
    with sync_playwright() as p:
        launched = p.chromium.launch(
            executable_path=path,
            headless=True,
            args=["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
        )
        try:
            yield launched
        finally:
            launched.close()


@pytest.fixture
def page(browser: Any, plant: Running) -> Iterator[Any]:
    context = browser.new_context(viewport={"width": 1280, "height": 800}, accept_downloads=True)
    tab = context.new_page()
    errors: list[str] = []
    tab.on("pageerror", lambda exc: errors.append(str(exc)))
    tab.set_default_timeout(20_000)
    try:
        yield tab
    finally:
        context.close()
    assert not errors, f"the page raised: {errors}"
