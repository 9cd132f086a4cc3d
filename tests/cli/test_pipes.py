"""Issue 20 item 9: a reader that goes away (``| head -1``) never ends in a traceback.

Every command that prints exits quietly with status 141 (128 + SIGPIPE) when
its output cannot be written; `fieldtwin run` keeps the plant serving and its
recording complete.  The real command in subprocesses, real pipes (some closed
before the command starts, so the outcome does not hang on a race), bounded waits.
"""

from __future__ import annotations

import os
import re
import select
import shlex
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from fieldtwin.cli import PIPE_CLOSED

ROOT = Path(__file__).resolve().parents[2]
PLANT = '[[tes]]\nmodel = "TES 8EA"\nslave = 2\nendpoint = "tcp://127.0.0.1:0"\n'
WAIT_S = 30.0
FIELDTWIN = [sys.executable, "-m", "fieldtwin"]
RUN = [*FIELDTWIN, "run", "plant.toml", "--no-live", "--no-control"]
STATUS = ["--status-every", "1", "--speed", "10"]  # a status line every 0.1 s of wall time


@pytest.fixture(scope="module")
def work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A plant file, a big trace and a short recording."""
    path = tmp_path_factory.mktemp("pipes")
    (path / "plant.toml").write_text(PLANT)
    example = (ROOT / "docs" / "trace-example.jsonl").read_text("utf-8")
    (path / "big.jsonl").write_text(example * 2000)  # ~1.2 MB of output: far beyond a pipe
    done = subprocess.run(
        [*RUN, "--speed", "max", "--duration", "2", "--record", "session.ftrec"],
        cwd=path,
        capture_output=True,
        text=True,
        timeout=WAIT_S,
    )
    assert done.returncode == 0, done.stderr
    return path


def _quiet(stderr: str) -> None:
    assert "Traceback" not in stderr, stderr
    assert "Exception ignored" not in stderr, stderr
    assert "BrokenPipeError" not in stderr, stderr


COMMANDS = {
    "trace show": ["trace", "show", "big.jsonl"],
    "tesis": ["tesis", "models"],
    "console": ["console", "plant.toml", "-c", "time", "-c", "tes 2 peek H'00C'"],
    "replay": ["replay", "session.ftrec"],
    "diff": ["diff", "session.ftrec", "session.ftrec"],
    "run": ["run", "plant.toml", "--duration", "1", "--no-live", "--no-control"],
    "help": ["--help"],  # argparse drops what it cannot write: status 0 or 141
}


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_command_exits_quietly_when_its_reader_is_gone(name: str, work: Path) -> None:
    read_end, write_end = os.pipe()
    os.close(read_end)  # nobody will ever read: the first write fails with EPIPE
    try:
        with (work / f"{name}.err").open("w+") as err:
            proc = subprocess.run(
                [*FIELDTWIN, *COMMANDS[name]],
                cwd=work,
                stdin=subprocess.DEVNULL,
                stdout=write_end,
                stderr=err,
                timeout=WAIT_S,
            )
            err.seek(0)
            stderr = err.read()
    finally:
        os.close(write_end)
    assert proc.returncode in ((0, PIPE_CLOSED) if name == "help" else (PIPE_CLOSED,)), stderr
    _quiet(stderr)


def test_trace_show_into_head(work: Path) -> None:
    command = shlex.join([*FIELDTWIN, "trace", "show", "big.jsonl"])
    done = subprocess.run(
        ["bash", "-c", f'{command} | head -1; echo "status ${{PIPESTATUS[0]}}" >&2'],
        cwd=work,
        capture_output=True,
        text=True,
        timeout=WAIT_S,
    )
    assert done.stdout.count("\n") == 1 and "read_holding_registers" in done.stdout
    _quiet(done.stderr)
    assert done.stderr.strip().endswith(f"status {PIPE_CLOSED}")


def test_run_with_status_lines_into_head_runs_to_its_end(work: Path) -> None:
    command = shlex.join([*RUN, *STATUS, "--duration", "10", "--record", "head.ftrec"])
    done = subprocess.run(
        ["bash", "-c", f'{command} | head -1; echo "status ${{PIPESTATUS[0]}}" >&2'],
        cwd=work,
        capture_output=True,
        text=True,
        timeout=WAIT_S,
    )
    assert done.stdout.startswith("listening: modbus-tcp") and done.stdout.count("\n") == 1
    _quiet(done.stderr)
    assert "the reader of the output went away" in done.stderr
    assert done.stderr.strip().endswith(f"status {PIPE_CLOSED}")
    _replays_whole(work, "head.ftrec", 10.0)


def _replays_whole(work: Path, recording: str, seconds: float) -> None:
    """The recording was closed complete: its replay is identical, to the last instant."""
    done = subprocess.run(
        [*FIELDTWIN, "replay", recording], cwd=work, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, (done.stdout, done.stderr)
    match = re.search(r"identical: .* (\d+) outputs recorded.*; ([\d.]+) simulated s", done.stdout)
    assert match is not None, done.stdout
    assert int(match.group(1)) > 0 and float(match.group(2)) >= seconds


def _fc03(sock: socket.socket, transaction: int) -> bytes:
    sock.sendall(struct.pack(">HHHBBHH", transaction, 0, 6, 2, 3, 0, 1))
    got = b""
    while len(got) < 6 or len(got) < 6 + struct.unpack(">H", got[4:6])[0]:
        data = sock.recv(260)
        assert data, "the plant hung up"
        got += data
    return got


@pytest.fixture
def plant_run(work: Path) -> Iterator[subprocess.Popen[str]]:
    err = (work / "serving.err").open("w+")
    proc = subprocess.Popen(
        [*RUN, *STATUS, "--record", "serving.ftrec"],
        cwd=work,
        stdout=subprocess.PIPE,
        stderr=err,
        text=True,
    )
    yield proc
    if proc.poll() is None:
        proc.kill()
        proc.wait(timeout=WAIT_S)
    err.close()


def _stderr_says(path: Path, needle: str) -> bool:
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        if needle in path.read_text():
            return True
        time.sleep(0.05)
    return False


def test_run_keeps_serving_after_its_reader_goes_away(
    work: Path, plant_run: subprocess.Popen[str]
) -> None:
    assert plant_run.stdout is not None
    assert select.select([plant_run.stdout], [], [], WAIT_S)[0]
    first = plant_run.stdout.readline()  # what `head -1` reads
    match = re.match(r"listening: modbus-tcp tcp://127\.0\.0\.1:(\d+) slaves 2", first)
    assert match, first
    plant_run.stdout.close()  # ... and head exits
    assert _stderr_says(work / "serving.err", "the reader of the output went away")
    with socket.create_connection(("127.0.0.1", int(match.group(1))), timeout=WAIT_S) as sock:
        for transaction in range(1, 4):  # across several status lines (one every 0.1 s)
            assert _fc03(sock, transaction)[7] == 3  # answered, not an exception
            time.sleep(0.3)
    assert plant_run.poll() is None  # still running
    plant_run.send_signal(signal.SIGTERM)
    assert plant_run.wait(timeout=WAIT_S) == PIPE_CLOSED
    stderr = (work / "serving.err").read_text()
    _quiet(stderr)
    assert stderr.count("the reader of the output went away") == 1  # said once
    _replays_whole(work, "serving.ftrec", 1.0)


def test_run_whose_output_and_errors_both_lose_their_reader(work: Path) -> None:
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        proc = subprocess.run(
            [*RUN, *STATUS, "--duration", "5", "--record", "both.ftrec"],
            cwd=work,
            stdout=write_end,
            stderr=write_end,
            timeout=WAIT_S,
        )
    finally:
        os.close(write_end)
    assert proc.returncode == PIPE_CLOSED
    _replays_whole(work, "both.ftrec", 5.0)
