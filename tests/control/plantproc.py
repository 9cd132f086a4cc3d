"""A real `fieldtwin run` in a subprocess: free ports, bounded waits, always torn down."""

from __future__ import annotations

import contextlib
import queue
import re
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import IO

ROOT = Path(__file__).resolve().parents[2]
START_S = 30.0


def default_plant_copy(tmp: Path) -> Path:
    """The embedded default plant, its Modbus TCP port left to the system (port 0)."""
    text = resources.files("fieldtwin").joinpath("plants", "default.toml").read_text("utf-8")
    path = tmp / "default.toml"
    path.write_text(text.replace("tcp://127.0.0.1:5020", "tcp://127.0.0.1:0"))
    return path


@dataclass
class Running:
    proc: subprocess.Popen[str]
    url: str = ""
    modbus_port: int = 0
    token: str | None = None
    lines: list[str] = field(default_factory=list)

    def alive(self) -> bool:
        return self.proc.poll() is None


def _read(stream: IO[str], lines: queue.Queue[str]) -> None:
    with contextlib.suppress(ValueError, OSError):
        for line in stream:
            lines.put(line)


@contextmanager
def fieldtwin_run(plant: Path, *extra: str) -> Iterator[Running]:
    with fieldtwin_run_with([sys.executable, "-m", "fieldtwin"], plant, ROOT, None, *extra) as r:
        yield r


@contextmanager
def fieldtwin_run_with(
    command: list[str], plant: Path, cwd: Path, env: dict[str, str] | None, *extra: str
) -> Iterator[Running]:
    """``COMMAND run PLANT --no-live --control-port 0 EXTRA...`` (an installed
    `fieldtwin` too), up to its `attach:` line."""
    proc = subprocess.Popen(
        [*command, "run", str(plant), "--no-live", "--control-port", "0", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=cwd,
        env=env,
    )
    running = Running(proc)
    try:
        assert proc.stdout is not None
        deadline = time.monotonic() + START_S
        lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=_read, args=(proc.stdout, lines), daemon=True).start()
        while not running.lines or not running.lines[-1].startswith("attach: "):
            assert time.monotonic() < deadline, f"no start within {START_S} s: {running.lines}"
            assert proc.poll() is None, f"fieldtwin run ended: {running.lines}"
            with contextlib.suppress(queue.Empty):
                line = lines.get(timeout=0.5).rstrip("\n")
                running.lines.append(line)
                if m := re.match(r"control: (http://\S+)$", line):
                    running.url = m.group(1)
                if m := re.match(r"listening: modbus-tcp tcp://127\.0\.0\.1:(\d+)", line):
                    running.modbus_port = int(m.group(1))
                if m := re.match(r"control token: (\S+)$", line):
                    running.token = m.group(1)
        yield running
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=5)
        for stream in (proc.stdout, proc.stderr):
            if stream is not None:
                stream.close()
