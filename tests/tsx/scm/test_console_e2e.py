"""End to end through the real command: `python -m fieldtwin console PLANT --speed 20 --script`.

The console wires channel 0 of a TSX SCM 2011 to a pty; the test reads the path from the
output of `status 7`, opens it with pyserial, and answers the prompt of a request 5
(SCM 4.3 transmission/reception with time-out), as a terminal would.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import serial

PLANT = """\
[plc]
model = "TSX 87"
scan_ms = 10

[[module]]
type = "TSX SCM 2011"
slot = 7
[[module.channels]]
channel = 0
endpoint = "pty"
config = ["H'0802'", "H'9600'", 0, "H'1001'", "H'1000'", "H'0D00'", 0, 0]
"""
# request 5: time-out H'0600' (60 s simulated = 3 s real at x20), 10 characters to receive,
# then the prompt "?>" to send (1st character in the low byte); the last `advance` keeps the
# pty open (0.5 s real) while the peer reads the echo
SCRIPT = """\
status 7
advance 10
exchange H'0700' 5 send H'0600' 10 H'3E3F' recv 10
read IW7,1
advance 10
"""
PTS = re.compile(r"(/dev/pts/\d+)")
DEADLINE_S = 20.0


def _read_until(port: serial.Serial, wanted: bytes, deadline: float) -> bytes:
    got = b""
    while wanted not in got and time.monotonic() < deadline:
        got += port.read(16)
    return got


def test_console_script_drives_a_reception_that_a_pty_peer_answers(tmp_path: Path) -> None:
    plant, script = tmp_path / "scm.toml", tmp_path / "scm.txt"
    plant.write_text(PLANT)
    script.write_text(SCRIPT)
    command = [sys.executable, "-m", "fieldtwin", "console", str(plant), "--speed", "20"]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    deadline = time.monotonic() + DEADLINE_S
    with subprocess.Popen(
        [*command, "--script", str(script)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    ) as proc:
        try:
            assert proc.stdout is not None
            path = None
            lines: list[str] = []
            while path is None and time.monotonic() < deadline:
                line = proc.stdout.readline()
                if not line:
                    break
                lines.append(line)
                if line.startswith("channel 0:"):
                    match = PTS.search(line)
                    path = match.group(1) if match else None
            assert path is not None, "".join(lines)
            with serial.Serial(path, 9600, timeout=0.2) as port:
                assert _read_until(port, b"?>", deadline).endswith(b"?>")  # the prompt
                port.write(b"hello\r")
                echo = _read_until(port, b"\r", deadline)
            out, err = proc.communicate(timeout=max(1.0, deadline - time.monotonic()))
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(5)
    assert proc.returncode == 0, err
    assert echo == b"hello\r"  # SCM 3.3 configuration: reception echo
    # report 1: stopped on ERC-1 (CR, not included); TXT0,S = 5 characters
    assert "TXT0,V = H'0001'  TXT0,S = 5  TXT0,E = 0" in out
    assert "text = 'hello'" in out
    assert "IW7,1 = H'1018'" in out  # channel 0 configured, SCA1 on both, both stopped
