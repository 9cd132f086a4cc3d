"""A user's project, as pytester builds it: fieldtwin installed, its plugin loaded by
the ``pytest11`` entry point (no ``-p``, no conftest), plants next to the tests."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"

PYPROJECT = """\
[project]
name = "myplant-tests"
version = "0"

[tool.pytest.ini_options]
testpaths = ["tests"]
pythonpath = ["."]
"""


def user_project(pytester: pytest.Pytester, *examples: str) -> Path:
    """pyproject.toml, tests/, plants/ with copies of the named examples/ files."""
    pytester.makefile(".toml", pyproject=PYPROJECT)
    plants = pytester.mkdir("plants")
    pytester.mkdir("tests")
    for name in examples:
        shutil.copy(EXAMPLES / name, plants / name)
    return pytester.path


def write(pytester: pytest.Pytester, relative: str, text: str) -> Path:
    path = pytester.path / relative
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path
