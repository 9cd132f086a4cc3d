"""docs/control.md and README's "Talking to it from other programs" tell the truth:
every curl line (and the event watcher) runs against a real `fieldtwin run`."""

from __future__ import annotations

import json
import os
import re
import select
import shlex
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.control.plantproc import ROOT, Running, default_plant_copy, fieldtwin_run
from tests.systools import require

PAGES = (ROOT / "docs" / "control.md", ROOT / "README.md")
README_URL = "http://127.0.0.1:8520"  # what README.md shows; replaced by the run's URL
STEP_S = 60
RUNNABLE = ("curl ", "fieldtwin console --attach", "python -m fieldtwin.control.watch", "wait")


def sh_lines(page: Path) -> list[str]:
    text = page.read_text("utf-8")
    if page.name == "README.md":  # only its section on the control API
        start = text.index("## Talking to it from other programs")
        end = text.find("\n## ", start + 1)
        text = text[start : end if end > 0 else None]
    blocks = re.findall(r"^```sh\n(.*?)^```", text, re.S | re.M)
    lines = [line for block in blocks for line in block.splitlines() if line.strip()]
    if page.name == "README.md":  # its other lines need a Modbus master or a terminal
        lines = [line for line in lines if line.startswith(RUNNABLE)]
    return lines


def test_the_pages_show_curl_examples() -> None:
    for page in PAGES:
        assert any(line.startswith("curl ") for line in sh_lines(page)), page.name


@pytest.fixture(scope="module")
def plant(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    require("curl")
    with fieldtwin_run(default_plant_copy(tmp_path_factory.mktemp("docs"))) as running:
        yield running


def run_line(line: str, url: str, background: list[subprocess.Popen[str]]) -> None:
    env = dict(os.environ, URL=url, FIELDTWIN_URL=url)
    command, _, comment = line.partition("  # ")
    command = command.replace(README_URL, url).replace("$FIELDTWIN_URL", url).strip()
    if command == "wait":
        for proc in background:
            out, err = proc.communicate(timeout=STEP_S)
            assert proc.returncode == 0, err
            events = [json.loads(text) for text in out.splitlines()]
            assert events and all("kind" in event for event in events), out
        background.clear()
        return
    if command.startswith("python -m fieldtwin.control.watch"):
        words = shlex.split(command.rstrip("&").replace("$URL", url))
        watcher = subprocess.Popen(
            [sys.executable, *words[1:]],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=ROOT,
        )
        background.append(watcher)
        assert watcher.stderr is not None
        # the watcher says when it is subscribed: the next lines publish after that
        ready, _, _ = select.select([watcher.stderr], [], [], STEP_S)
        said = watcher.stderr.readline() if ready else ""
        assert said.startswith("subscribed: "), (line, said)
        return
    if command.startswith("fieldtwin "):
        words = shlex.split(command)
        done = subprocess.run(
            [sys.executable, "-m", "fieldtwin", *words[1:]],
            capture_output=True,
            text=True,
            timeout=STEP_S,
            cwd=ROOT,
            check=False,
        )
        assert done.returncode == 0, (line, done.stderr)
        assert done.stdout.strip(), line
        return
    assert command.startswith("curl "), f"not a runnable example: {line!r}"
    expected = int(comment) if comment.strip().isdigit() else None
    full = "curl -w '\\n%{http_code}' " + command[len("curl ") :]
    done = subprocess.run(
        ["bash", "-c", full],
        capture_output=True,
        text=True,
        timeout=STEP_S,
        env=env,
        check=False,
    )
    assert done.returncode == 0, (line, done.stderr)
    body, _, status = done.stdout.rpartition("\n")
    assert body.strip(), line
    json.loads(body)
    if expected is None:
        assert 200 <= int(status) < 300, (line, status, body)
    else:
        assert int(status) == expected, (line, status, body)


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_every_example_runs_against_a_real_plant(plant: Running, page: Path) -> None:
    background: list[subprocess.Popen[str]] = []
    try:
        for line in sh_lines(page):
            run_line(line, plant.url, background)
        assert not background, "a watcher without a `wait`"
    finally:
        for proc in background:
            proc.kill()
            proc.wait(timeout=10)
    assert plant.alive()
