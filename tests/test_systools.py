"""A missing system tool skips its test (with the summary line's marker), or fails it
with CI=true: in CI nothing is skipped."""

from __future__ import annotations

import pytest

from tests.systools import SKIP_PREFIX, require

MISSING = "fieldtwin-no-such-tool"


def test_a_missing_tool_skips_outside_ci(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception) as skipped:
        require(MISSING)
    assert str(skipped.value) == SKIP_PREFIX + MISSING


def test_a_missing_tool_fails_in_ci(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception) as failed:
        require(MISSING)
    assert "CI=true" in str(failed.value) and f"apt-get install -y {MISSING}" in str(failed.value)


def test_a_present_tool_is_found(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CI", "true")
    assert require("sh").endswith("/sh")
