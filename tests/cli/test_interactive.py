"""The interactive console on a real terminal (a pty), as a person uses it."""

from __future__ import annotations

import fcntl
import os
import select
import subprocess
import sys
import termios
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _read_until(fd: int, marker: bytes, limit_s: float = 60.0) -> bytes:
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


SELECT_SYSCALLS = {"7", "23", "270", "271"}  # poll, select, pselect6, ppoll (x86_64)


def _wait_in_select(pid: int, limit_s: float = 30.0) -> None:
    """Until the process waits for input in its select (bounded), from /proc/PID/syscall."""
    deadline = time.monotonic() + limit_s
    while time.monotonic() < deadline:
        with open(f"/proc/{pid}/syscall") as file:
            if file.read().split(" ", 1)[0] in SELECT_SYSCALLS:
                return
        select.select([], [], [], 0.005)
    raise AssertionError(f"process {pid} never waited for input")


def _console_on_a_terminal(tmp_path: Path) -> tuple[subprocess.Popen[bytes], int]:
    """The console with the pty as its controlling terminal, so that ^C is a SIGINT."""
    plant = tmp_path / "p.toml"
    plant.write_text('[plc]\nmodel = "TSX 87"\nscan_ms = 1\n')
    master, slave = os.openpty()
    env = dict(os.environ, HOME=str(tmp_path), TERM="dumb")

    def controlling_terminal() -> None:
        os.setsid()
        fcntl.ioctl(0, termios.TIOCSCTTY, 0)

    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldtwin", "console", str(plant)],
        stdin=slave,
        stdout=slave,
        stderr=slave,
        cwd=ROOT,
        env=env,
        close_fds=True,
        preexec_fn=controlling_terminal,
    )
    os.close(slave)
    return proc, master


def test_ctrl_c_interrupts_advance_and_keeps_the_plant(tmp_path: Path) -> None:
    # issue 10 item 20: Ctrl-C ended the session (status 0) and the plant was lost
    proc, master = _console_on_a_terminal(tmp_path)
    try:
        _read_until(master, b"fieldtwin> ")
        os.write(master, b"write W7 42\n")
        assert b"W7 = 42" in _read_until(master, b"fieldtwin> ")
        os.write(master, b"advance 100h\n")  # hours of 1 ms scans: far longer than the test
        _read_until(master, b"(Ctrl-C interrupts)")
        os.write(master, b"\x03")
        out = _read_until(master, b"fieldtwin> ")
        assert b"interrupted  t = " in out
        stopped = float(out.split(b"interrupted  t = ")[1].split(b" s")[0])
        assert 0 < stopped < 360_000
        os.write(master, b"read W7\n")  # the same plant, the same session
        assert b"W7 = 42" in _read_until(master, b"fieldtwin> ")
        os.write(master, b"time\n")
        assert f"t = {stopped:.3f} s".encode() in _read_until(master, b"fieldtwin> ")
        os.write(master, b"adv")  # at the prompt: the line is dropped, the session stays
        _read_until(master, b"adv")  # echoed: readline has the line
        _wait_in_select(proc.pid)  # CPython's readline misses a SIGINT taken outside its select
        os.write(master, b"\x03")
        assert b"^C" in _read_until(master, b"fieldtwin> ")
        os.write(master, b"read W7\n")
        assert b"W7 = 42" in _read_until(master, b"fieldtwin> ")
        assert proc.poll() is None
        os.write(master, b"\x04")  # Ctrl-D leaves
        assert proc.wait(timeout=20) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=5)
        os.close(master)
