"""Headless Chromium for the dashboard tests: Debian's chromium driven by Playwright.

No browser is downloaded (`playwright install` is never run): the tests use the
system's ``chromium`` (or ``$FIELDTWIN_CHROMIUM``).  When none is found the tests
FAIL with how to install one; they never pass without a browser.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = ROOT / "test-artifacts" / "dashboard"
INSTALL = (
    "no chromium found for the dashboard's browser tests: install Debian's"
    " (`sudo apt-get install chromium`; .ci/run does it), or point"
    " FIELDTWIN_CHROMIUM at a Chromium binary"
)


def chromium_path() -> str | None:
    given = os.environ.get("FIELDTWIN_CHROMIUM")
    if given:
        return given if Path(given).is_file() else None
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return None


def artifact(name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    return ARTIFACTS / name
