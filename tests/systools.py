"""System tools some tests need (tshark, chromium, curl): found, or the test is skipped.

`make test` installs them first where it can (as root on Debian: .ci/test-tools).
Where it cannot, the tests that need them are skipped and the run ends with ONE line
naming what to install (tests/markers.py).  With CI=true a missing tool fails the
test instead: in CI nothing is skipped.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

SKIP_PREFIX = "needs a system tool: "
PACKAGES = {"tshark": "tshark", "chromium": "chromium", "curl": "curl"}


def in_ci() -> bool:
    return os.environ.get("CI", "").strip().lower() in ("1", "true", "yes")


def chromium_path() -> str | None:
    """The system's Chromium (or ``$FIELDTWIN_CHROMIUM``); no browser is ever downloaded."""
    given = os.environ.get("FIELDTWIN_CHROMIUM")
    if given:
        return given if Path(given).is_file() else None
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return None


def require(tool: str) -> str:
    """The path of ``tool``; else skip the test (fail it under CI=true) naming the package."""
    path = chromium_path() if tool == "chromium" else shutil.which(tool)
    if path is not None:
        return path
    hint = f"{tool} (apt-get install -y {PACKAGES.get(tool, tool)})"
    if in_ci():
        pytest.fail(f"CI=true and {tool} is missing: .ci/run installs it; {hint}", pytrace=False)
    pytest.skip(SKIP_PREFIX + tool)
