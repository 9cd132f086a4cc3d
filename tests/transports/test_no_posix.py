"""POSIX-only modules stay with the pty transport: a TCP-only plant runs, and the console
drives it, in a Python where pty, termios, fcntl and tty cannot be imported (as on
Windows)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.control.plantproc import ROOT

BLOCKED = ("pty", "termios", "fcntl", "tty")
SITECUSTOMIZE = f"""
import sys

BLOCKED = {BLOCKED!r}


class _NoPosix:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ImportError(f"No module named {{name!r}} (blocked: a system without POSIX)")
        return None


sys.meta_path.insert(0, _NoPosix())
for name in BLOCKED:
    sys.modules.pop(name, None)
"""
PLANT = """
[plc]
model = "TSX 87"
scan_ms = 10

[[module]]
type = "TSX AEM 811"
slot = 5

[[tes]]
model = "TES 8EA"
slave = 2
endpoint = "tcp://127.0.0.1:0"

[[tes]]
model = "TES 32EST"
slave = 3
endpoint = "rtu+tcp://127.0.0.1:0"
"""


def _python(tmp_path: Path, *argv: str) -> subprocess.CompletedProcess[str]:
    blocker = tmp_path / "noposix"
    blocker.mkdir(exist_ok=True)
    (blocker / "sitecustomize.py").write_text(SITECUSTOMIZE, "utf-8")
    path = [str(blocker), *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))]
    return subprocess.run(
        [sys.executable, *argv],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
        env=dict(os.environ, PYTHONPATH=os.pathsep.join(path)),
        stdin=subprocess.DEVNULL,
        check=False,
    )


@pytest.mark.integration
def test_the_blocker_blocks(tmp_path: Path) -> None:
    for name in BLOCKED:
        done = _python(tmp_path, "-c", f"import {name}")
        assert done.returncode != 0 and "blocked" in done.stderr, (name, done.stderr)


@pytest.mark.integration
def test_a_tcp_plant_runs_and_the_console_drives_it_without_posix_modules(
    tmp_path: Path,
) -> None:
    plant = tmp_path / "tcp.toml"
    plant.write_text(PLANT, "utf-8")
    done = _python(
        tmp_path, "-m", "fieldtwin", "run", str(plant), "--speed", "max", "--duration", "12",
        "--no-live", "--control-port", "0",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "listening: modbus-tcp tcp://127.0.0.1:" in done.stdout, done.stdout
    assert "control: http://127.0.0.1:" in done.stdout, done.stdout
    assert done.stdout.splitlines()[-1].startswith("stopped at t = 12."), done.stdout
    done = _python(
        tmp_path, "-m", "fieldtwin", "console", str(plant), "--speed", "max",
        "-c", "advance 12", "-c", "read IW5,0,C", "-c", "tes 2 input a1 4.5", "-c", "tes 2 leds",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[:3] == ["t = 12.000 s", "IW5,0,C = 0", "tes 2 input a1 = 4.5"], lines
    assert lines[3].startswith("Pwr=on Run=on"), lines
    check = _python(
        tmp_path, "-c",
        "import sys, fieldtwin.cli, fieldtwin.console, fieldtwin.transports,"
        " fieldtwin.runtime.runner, fieldtwin.control.launch; "
        f"print(sorted(set(sys.modules) & set({BLOCKED!r})))",
    )  # fmt: skip
    assert check.returncode == 0 and check.stdout.strip() == "[]", (check.stdout, check.stderr)
