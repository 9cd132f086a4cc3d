"""`make run`: a plant's own [run] speed holds unless SPEED= is given (issue 10 item 17)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _dry_run(*args: str) -> str:
    if shutil.which("make") is None:
        pytest.fail("make is not installed (apt-get install make)")
    done = subprocess.run(
        ["make", "-n", "-o", ".venv/.installed", "run", *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=30,
        check=True,
    )
    return done.stdout


def test_make_run_passes_no_speed_unless_asked() -> None:
    line = _dry_run("PLANT=examples/aem811.toml")
    assert "fieldtwin run examples/aem811.toml" in line
    assert "--speed" not in line


def test_make_run_speed_overrides() -> None:
    assert "--speed 10" in _dry_run("SPEED=10")


def _dry(target: str) -> str:
    if shutil.which("make") is None:
        pytest.fail("make is not installed (apt-get install make)")
    return subprocess.run(
        ["make", "-n", "-o", ".venv/.installed", target],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=30,
        check=True,
    ).stdout


def test_make_test_runs_in_parallel_after_the_tools_and_test_fast_leaves_out_integration() -> None:
    full = _dry("test")
    assert ".ci/test-tools" in full and "pytest -n auto" in full, full
    assert full.index(".ci/test-tools") < full.index("pytest"), full
    fast = _dry("test-fast")
    assert '-m "not integration"' in fast, fast


def test_ci_runs_lint_and_the_full_test() -> None:
    text = (ROOT / ".ci" / "run").read_text("utf-8")
    assert "make lint" in text and "make test " in text and "test-fast" not in text
    assert 'CI="${CI:-true}"' in text
