"""docs/testing.md tells the truth: its example project (every code block whose first
line is ``# path/file``) is written into a fresh project and its tests pass."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from tests.plugin.project import EXAMPLES, ROOT

PAGE = ROOT / "docs" / "testing.md"
FILE_LINE = re.compile(r"^# ([\w./-]+\.(?:py|toml))\n")


def files_on_the_page() -> dict[str, str]:
    blocks = re.findall(r"^```(?:python|toml)\n(.*?)^```", PAGE.read_text(), re.S | re.M)
    found: dict[str, str] = {}
    for block in blocks:
        match = FILE_LINE.match(block)
        if match is not None:
            assert match.group(1) not in found, f"{match.group(1)} twice on the page"
            found[match.group(1)] = block
    return found


def test_the_page_shows_the_poller_and_the_plc_program_projects() -> None:
    files = files_on_the_page()
    assert {
        "pyproject.toml",
        "plants/station.toml",
        "scada/poller.py",
        "tests/test_poller.py",
        "plants/tank.toml",
        "tests/test_tank_program.py",
    } <= set(files)
    assert "running_plant" in files["tests/test_poller.py"]
    assert "pymodbus" in files["scada/poller.py"]
    assert 'program = "aem811_tank.pl7"' in files["plants/tank.toml"]


def test_the_example_project_passes(pytester: pytest.Pytester) -> None:
    files = files_on_the_page()
    for name, text in files.items():
        path = pytester.path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    shutil.copy(EXAMPLES / "aem811_tank.pl7", pytester.path / "plants" / "aem811_tank.pl7")
    tests = sum(text.count("\ndef test_") for name, text in files.items() if "tests/" in name)
    assert tests >= 5
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-v")
    result.assert_outcomes(passed=tests)


def test_the_page_quotes_the_messages_the_helpers_give() -> None:
    text = PAGE.read_text()
    # the same lines tests/plugin/test_plugin.py checks in a real run (path shortened)
    for line in (
        'lambda: plc.read("W0") > 9000 not true within 20 s (from t = 0.000 s to t = 20.000 s)',
        "  last value of the predicate: False",
        "at t = 20.000 s: W0 = 5001 (H'1389'), IW5,0,C = 1",
        "expected 7000 (H'1B58'), actual 5001 (H'1389') at t = 12.000 s",
        "expected 'on', actual 'off' (OK=on ERR=off F=off) at t = 12.000 s",
    ):
        assert line in text, line


def test_the_page_is_listed_in_the_readme() -> None:
    readme = (ROOT / "README.md").read_text()
    assert "docs/testing.md" in readme
    assert "## Testing your own code" in readme
    assert Path(PAGE).name in readme
