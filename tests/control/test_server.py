"""The control listener's port: a busy default falls back, a busy given port is an error;
an attached console that cannot reach its plant says so with status 2."""

from __future__ import annotations

import socket
import subprocess
import sys

import pytest

from fieldtwin.control.server import bind_control
from fieldtwin.errors import ConfigError
from tests.control.plantproc import ROOT


def test_a_busy_port_falls_back_to_a_free_one_only_when_it_was_not_given() -> None:
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen()
    port = busy.getsockname()[1]
    try:
        other = bind_control("127.0.0.1", port, fallback=True)
        assert other.getsockname()[1] not in (0, port)
        other.close()
        with pytest.raises(ConfigError, match=rf"--control-port {port}: cannot listen"):
            bind_control("127.0.0.1", port, fallback=False)
    finally:
        busy.close()


def test_attaching_to_no_plant_exits_2_naming_the_url() -> None:
    free = socket.socket()
    free.bind(("127.0.0.1", 0))
    port = free.getsockname()[1]
    free.close()  # nobody listens there now
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "fieldtwin",
            "console",
            "--attach",
            f"http://127.0.0.1:{port}",
            "-c",
            "time",
        ],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
        check=False,
    )
    assert done.returncode == 2
    assert f"http://127.0.0.1:{port}: cannot reach the control API" in done.stderr
    assert "Traceback" not in done.stderr
