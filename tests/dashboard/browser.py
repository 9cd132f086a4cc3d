"""Headless Chromium for the dashboard tests: Debian's chromium driven by Playwright.

No browser is downloaded (`playwright install` is never run): the tests use the
system's ``chromium`` (or ``$FIELDTWIN_CHROMIUM``).  When none is found the tests are
skipped, with one line at the end naming what to install; with CI=true they fail
(tests/systools.py).  They never pass without a browser.
"""

from __future__ import annotations

from pathlib import Path

from tests.systools import chromium_path

ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = ROOT / "test-artifacts" / "dashboard"


def artifact(name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    return ARTIFACTS / name


__all__ = ["ARTIFACTS", "artifact", "chromium_path"]
