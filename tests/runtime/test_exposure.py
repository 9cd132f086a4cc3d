"""Issue 10 item 7: listeners reachable from other machines are named in a warning."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from fieldtwin.runtime.exposure import exposed, warnings_for
from fieldtwin.runtime.modbus_server import url_of
from fieldtwin.transports.url import parse_endpoint


def test_loopback_listeners_get_no_warning() -> None:
    lines = [
        "listening: modbus-tcp tcp://127.0.0.1:5020 slaves 1",
        "listening: modbus-rtu-over-tcp rtu+tcp://[::1]:5021 slaves 2 (9600 8E1)",
        "listening: TSX SCM 2011 slot 7 channel 0 tcp://localhost:5000 (waiting)",
        "listening: modbus-rtu pty /dev/pts/3 slaves 1 (9600 8E1)",
    ]
    assert warnings_for(lines) == []


def test_every_listener_reachable_from_other_machines_is_named() -> None:
    lines = [
        "listening: modbus-tcp tcp://0.0.0.0:5020 slaves 1",
        "listening: modbus-rtu-over-tcp rtu+tcp://[::]:5021 slaves 2 (9600 8E1)",
        "listening: TSX SCM 2011 slot 7 channel 1 tcp://192.168.1.20:5001 (waiting)",
        "listening: modbus-tcp tcp://127.0.0.1:5022 slaves 3",
    ]
    found = exposed(lines)
    assert [url for url, _ in found] == [
        "tcp://0.0.0.0:5020",
        "rtu+tcp://[::]:5021",
        "tcp://192.168.1.20:5001",
    ]
    warnings = warnings_for(lines)
    assert len(warnings) == 3 and all("reachable from other machines" in w for w in warnings)
    assert "every interface" in warnings[0] and "192.168.1.20" in warnings[2]


class _Bound:
    """A listener bound to the IPv6 wildcard, as getsockname() reports it."""

    name = "tcp-v6"
    address = ("::", 25951)

    def accept(self) -> None:
        return None

    def fileno(self) -> int:
        return -1

    def close(self) -> None:
        pass


def test_an_ipv6_listening_url_parses_back() -> None:
    url = url_of("tcp", _Bound())
    assert url == "tcp://[::]:25951"  # not tcp://:::25951
    endpoint = parse_endpoint(url)
    assert (endpoint.scheme, endpoint.host, endpoint.port) == ("tcp", "::", 25951)
    assert url_of("rtu+tcp", _Bound()) == "rtu+tcp://[::]:25951"
    assert warnings_for([f"listening: modbus-tcp {url} slaves 1"])


PLANT = """\
[[tes]]
model = "TES 32EST"
slave = 1
endpoint = "tcp://0.0.0.0:0"

[[tes]]
model = "TES 16EST"
slave = 2
endpoint = "tcp://127.0.0.1:0"
"""


def test_fieldtwin_run_warns_about_a_wildcard_listener(tmp_path: Path) -> None:
    plant = tmp_path / "open.toml"
    plant.write_text(PLANT)
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "fieldtwin",
            "run",
            str(plant),
            "--duration",
            "0.2",
            "--control-port",
            "0",
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    warned = [line for line in done.stderr.splitlines() if line.startswith("warning:")]
    assert len(warned) == 1 and "tcp://0.0.0.0:" in warned[0]
    assert "tcp://127.0.0.1" not in warned[0]
