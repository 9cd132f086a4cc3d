"""The OpenAPI document is the API (docs/control.md): schemathesis, every check, against a
real `fieldtwin run`, while a pymodbus master polls the plant and counts failed polls.

Excluded, because they cannot be fuzzed without stopping what the poller measures:

* ``POST /clock/pause`` holds simulated time, and with it every Modbus answer until a
  ``resume`` (by design: docs/control.md, "The clock"); a fuzzer's pause would fail polls.
* ``PUT /clock/speed``: a valid factor of 0.001 makes a TES answer a thousand times later
  in wall time (its turnaround is simulated time), so polls would time out by design.

Both have their own tests (tests/hardening/test_reachable.py, test_blackbox.py).  A valid
``wait_s`` is sent as 1 s (tests/control/st_hooks.py) so that no case waits an hour.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

from pymodbus.client import ModbusTcpClient
from pymodbus.exceptions import ConnectionException, ModbusIOException

from tests.control.plantproc import ROOT, default_plant_copy, fieldtwin_run

RUN_S = 240.0  # the bound on schemathesis's run (it takes about a minute)
POLL_S = 0.05
EXCLUDED = ("/clock/pause", "/clock/speed")


class Poller:
    """A Modbus master reading a TES word every POLL_S until stopped; counts failures."""

    def __init__(self, port: int) -> None:
        self.port = port
        self.polls = 0
        self.failed: list[str] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        client = ModbusTcpClient("127.0.0.1", port=self.port, timeout=2, retries=0)
        try:
            while not self._stop.is_set():
                if not client.connected:
                    client.connect()  # type: ignore[no-untyped-call]
                try:
                    reply = client.read_holding_registers(0x005, count=1, device_id=1)
                    if reply.isError():
                        self.failed.append(f"poll {self.polls}: {reply}")
                except (ModbusIOException, ConnectionException) as exc:
                    self.failed.append(f"poll {self.polls}: {exc}")
                self.polls += 1
                self._stop.wait(POLL_S)
        finally:
            client.close()  # type: ignore[no-untyped-call]

    def __enter__(self) -> Poller:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(10)


def test_schemathesis_finds_no_failure_and_modbus_keeps_answering(tmp_path: Path) -> None:
    plant = default_plant_copy(tmp_path)
    with fieldtwin_run(plant) as running, Poller(running.modbus_port) as poller:
        command = [
            str(Path(sys.executable).with_name("schemathesis")),
            "run",
            f"{running.url}/openapi.json",
            "--checks",
            "all",
            "--max-examples",
            "5",
            "--seed",
            "20",
            "--generation-deterministic",
            "--request-timeout",
            "15",
            "--continue-on-failure",
            "--no-color",
            "--report-dir",
            str(tmp_path / "report"),
        ]
        for path in EXCLUDED:
            command += ["--exclude-path", path]
        env = dict(os.environ, SCHEMATHESIS_HOOKS="tests.control.st_hooks", PYTHONPATH=str(ROOT))
        env["PYTHONPATH"] += os.pathsep + os.environ.get("PYTHONPATH", "")
        started = time.monotonic()
        done = subprocess.run(
            command,
            capture_output=True,
            text=True,
            timeout=RUN_S,
            cwd=tmp_path,
            env=env,
            check=False,
        )
        took = time.monotonic() - started
        alive = running.alive()
    report = done.stdout[-6000:] + done.stderr[-2000:]
    assert done.returncode == 0, report
    assert "no failures" in done.stdout.lower() or " passed" in done.stdout, report
    assert alive, "the plant ended during the run"
    assert poller.polls > took / (POLL_S + 2.0), (poller.polls, took)
    assert poller.failed == [], poller.failed[:10]
