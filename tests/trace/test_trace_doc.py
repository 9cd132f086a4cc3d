"""docs/trace.md tells the truth: its `fieldtwin trace show` examples print what it shows,
and every field its tables name is one the example trace has."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from fieldtwin.runtime.trace import read_records

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "trace.md"


def console_blocks() -> list[tuple[list[str], list[str]]]:
    found = []
    for block in re.findall(r"^```console\n(.*?)^```", PAGE.read_text(), re.S | re.M):
        lines = block.splitlines()
        assert lines[0].startswith("$ fieldtwin trace show "), lines[0]
        found.append((shlex.split(lines[0][2:])[1:], lines[1:]))
    return found


BLOCKS = console_blocks()


def test_the_page_shows_trace_show() -> None:
    assert len(BLOCKS) >= 2


@pytest.mark.parametrize(("argv", "expected"), BLOCKS, ids=[" ".join(a) for a, _ in BLOCKS])
def test_trace_show_prints_what_the_page_shows(argv: list[str], expected: list[str]) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "fieldtwin", *argv],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
        check=True,
    )
    assert done.stdout.splitlines() == expected


def test_the_example_trace_has_the_fields_the_page_names() -> None:
    records = read_records(ROOT / "docs" / "trace-example.jsonl")
    have = {key for r in records for key in r}
    text = PAGE.read_text()
    for key in (
        "t",
        "wall",
        "kind",
        "device",
        "endpoint",
        "dir",
        "transport",
        "listen",
        "conn",
        "slave",
        "transaction",
        "hex",
        "function",
        "function_name",
        "address",
        "count",
        "exception",
        "tes",
        "from",
    ):
        assert key in have, key
        assert f"| `{key}`" in text or f"`{key}`," in text or f", `{key}`" in text, key
