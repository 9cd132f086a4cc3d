"""The interactive console on a real terminal (a pty), as a person uses it."""

from __future__ import annotations

import os
import select
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _read_until(fd: int, marker: bytes, limit_s: float = 20.0) -> bytes:
    data = b""
    deadline = time.monotonic() + limit_s
    while marker not in data:
        remaining = deadline - time.monotonic()
        assert remaining > 0, f"no {marker!r} in {data!r}"
        ready, _, _ = select.select([fd], [], [], remaining)
        if ready:
            try:
                chunk = os.read(fd, 4096)
            except OSError:
                break
            if not chunk:
                break
            data += chunk
    return data


def test_interactive_session_with_help_errors_and_quit(tmp_path: Path) -> None:
    plant = tmp_path / "p.toml"
    plant.write_text('[plc]\nmodel = "TSX 87"\n')
    master, slave = os.openpty()
    env = dict(os.environ, HOME=str(tmp_path), TERM="dumb")
    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldtwin", "console", str(plant)],
        stdin=slave,
        stdout=slave,
        stderr=slave,
        cwd=ROOT,
        env=env,
        close_fds=True,
    )
    os.close(slave)
    try:
        _read_until(master, b"fieldtwin> ")
        os.write(master, b"advance 1.5s\n")
        assert b"t = 1.500 s" in _read_until(master, b"fieldtwin> ")
        os.write(master, b"read IW9,0\n")
        assert b"error: 'IW9,0'" in _read_until(master, b"fieldtwin> ")
        os.write(master, b"help advance\n")
        assert b"advance DURATION" in _read_until(master, b"fieldtwin> ")
        os.write(master, b"quit\n")
        assert proc.wait(timeout=20) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=5)
        os.close(master)
    assert (tmp_path / ".fieldtwin_history").exists()
