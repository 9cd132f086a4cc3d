"""SCM 4.6 end to end: the program sends and receives its strings against a pty peer."""

from __future__ import annotations

import os
import re
import select
import subprocess
import sys
import time
import tty
from pathlib import Path

from fieldtwin.devices.scm.status import endpoint_lines
from fieldtwin.plant import load_plant

ROOT = Path(__file__).resolve().parents[3]
PLANT = ROOT / "examples" / "scm_exchange.toml"


def _words_text(read: object, first: int, count: int) -> bytes:
    assert callable(read)
    return b"".join(int(read(f"W{first + k}")).to_bytes(2, "little") for k in range(count))


def test_the_program_sends_hello_and_keeps_what_the_peer_types() -> None:
    plant = load_plant(PLANT, speed=None)
    try:
        plc = plant.plc
        assert plc is not None
        plc.advance(12.0)
        assert plc.read("B0") == 1  # SR17: the channel configured (TXT1 answered H'FE')
        path = endpoint_lines(plc.module(0, 2))[0].split()[-1]
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        try:
            tty.setraw(fd)
            plc.write("B128", 1)  # SR5: send (SR8 puts "HELLO" after the two words at 0)
            got = b""
            for _ in range(200):
                plc.advance(0.05)
                if select.select([fd], [], [], 0)[0]:
                    got += os.read(fd, 100)
                if b"HELLO" in got:
                    break
            assert got == b"HELLO" and plc.read("B128") == 0
            os.write(fd, b"ABCDE")  # SR7: a 5-character reception, SR9 keeps it
            for _ in range(200):
                plc.advance(0.05)
                if plc.read("W1210"):
                    break
            assert plc.read("W1210") == 1
            assert _words_text(plc.read, 1200, 3)[:5] == b"ABCDE"
        finally:
            os.close(fd)
    finally:
        plant.close()


def test_fieldtwin_run_receives_from_a_pty_peer_as_a_subprocess() -> None:
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "fieldtwin",
            "run",
            str(PLANT),
            "--no-live",
            "--status-every",
            "0.5",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )
    try:
        assert proc.stdout is not None
        path, lines = None, []
        deadline = time.monotonic() + 60
        while path is None and time.monotonic() < deadline:
            line = proc.stdout.readline()
            lines.append(line)
            found = re.search(r"channel 1 pty (\S+)", line)
            path = found.group(1) if found else None
        assert path is not None, lines
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        try:
            tty.setraw(fd)
            seen = ""
            while time.monotonic() < deadline and "B0=0001" not in seen:
                seen = proc.stdout.readline()  # configured once the self-test is over
            os.write(fd, b"ABCDE")
            while time.monotonic() < deadline and "W1210=0001" not in seen:
                seen = proc.stdout.readline()
            assert "W1210=0001 W1200=4241 W1201=4443" in seen, seen
        finally:
            os.close(fd)
    finally:
        proc.terminate()
        proc.wait(timeout=20)
