"""Issue 20 R10: 256 idle connections never lock a new master out of a running plant.

A real ``fieldtwin run`` serves a TES on Modbus TCP; 256 masters connect, ask
once and then sit idle (the documented limit per endpoint); one more master
connects and is answered, and the longest-idle connection is the one hung up,
with a FIN.  Every wait is bounded.
"""

from __future__ import annotations

import re
import resource
import select
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

from fieldtwin.transports.tcp import DEFAULT_MAX_CONNECTIONS

ROOT = Path(__file__).resolve().parents[2]
PLANT = '[[tes]]\nmodel = "TES 8EA"\nslave = 2\nendpoint = "tcp://127.0.0.1:0"\n'
WAIT_S = 10.0


def _raise_fd_limit(needed: int) -> None:
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft != resource.RLIM_INFINITY and soft < needed:
        resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))  # the child inherits it


def _fc03(transaction: int) -> bytes:
    return struct.pack(">HHHBBHH", transaction, 0, 6, 2, 3, 0, 1)


def _answer(sock: socket.socket, transaction: int) -> bytes:
    """One MBAP answer to ``transaction`` (bounded wait)."""
    sock.settimeout(WAIT_S)
    got = b""
    while len(got) < 6 or len(got) < 6 + struct.unpack(">H", got[4:6])[0]:
        data = sock.recv(260)
        assert data, "the connection ended before the answer"
        got += data
    assert struct.unpack(">H", got[:2])[0] == transaction
    return got


def _port(proc: subprocess.Popen[str]) -> int:
    assert proc.stdout is not None
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        if select.select([proc.stdout], [], [], 0.5)[0]:
            line = proc.stdout.readline()
            match = re.match(r"listening: modbus-tcp tcp://127\.0\.0\.1:(\d+) slaves 2", line)
            if match:
                return int(match.group(1))
            assert line, "fieldtwin run ended before it listened"
    raise AssertionError("no Modbus TCP endpoint announced")


def test_256_idle_connections_and_a_new_master_is_answered(tmp_path: Path) -> None:
    _raise_fd_limit(4 * DEFAULT_MAX_CONNECTIONS)
    (tmp_path / "plant.toml").write_text(PLANT)
    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldtwin", "run", "plant.toml", "--no-live", "--no-control"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    idle: list[socket.socket] = []
    try:
        address = ("127.0.0.1", _port(proc))
        for n in range(DEFAULT_MAX_CONNECTIONS):
            sock = socket.create_connection(address, timeout=WAIT_S)
            idle.append(sock)
            sock.sendall(_fc03(n + 1))  # answered: the plant holds this connection open
            _answer(sock, n + 1)
        # every slot is taken by a connection that is idle now; a new master comes
        newcomer = socket.create_connection(address, timeout=WAIT_S)
        idle.append(newcomer)
        started = time.monotonic()
        newcomer.sendall(_fc03(7))
        answer = _answer(newcomer, 7)
        assert answer[7] == 3 and time.monotonic() - started < WAIT_S  # FC03, not an exception
        # the longest-idle one (the first to have asked) made room, with an orderly end
        idle[0].settimeout(WAIT_S)
        assert idle[0].recv(1) == b""
        idle[1].sendall(_fc03(1000))  # the others are still served
        assert _answer(idle[1], 1000)[7] == 3
    finally:
        for sock in idle:
            sock.close()
        proc.terminate()
        try:
            _, err = proc.communicate(timeout=WAIT_S)
        finally:
            proc.kill()
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    assert f"{DEFAULT_MAX_CONNECTIONS} connections open (the limit)" in err
    assert err.count("connections open (the limit)") == 1  # said once
