"""`console --attach` on a plant that wants its token: the refusal says to use --token."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests.control.plantproc import ROOT, default_plant_copy, fieldtwin_run


def _attach(url: str, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "fieldtwin", "console", "--attach", url, *extra],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
        stdin=subprocess.DEVNULL,
        check=False,
    )


def test_attach_without_the_token_says_to_use_token(tmp_path: Path) -> None:
    plant = default_plant_copy(tmp_path)
    with fieldtwin_run(plant, "--control-token", "s3cret", "--speed", "max") as running:
        done = _attach(running.url, "-c", "time")
        assert done.returncode == 2
        assert "use --token TOKEN" in done.stderr, done.stderr
        wrong = _attach(running.url, "--token", "nope", "-c", "time")
        assert wrong.returncode == 2
        assert "not this plant's" in wrong.stderr, wrong.stderr
        right = _attach(running.url, "--token", "s3cret", "-c", "time")
        assert right.returncode == 0, right.stderr
        assert right.stdout.startswith("t = "), right.stdout
