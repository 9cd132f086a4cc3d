"""Issue 20 R2: a PL7 program looping forever, in a real `fieldtwin run`.

From a plant file and through the control API (``prog load -`` with the text): the
PLC is in its watchdog fault, a pymodbus poller keeps getting answers (worst gap
<= 1 s), the API says why, SIGTERM ends the process within 2 s.  Every wait bounded.
"""

from __future__ import annotations

import signal
import threading
import time
from itertools import pairwise
from pathlib import Path

import httpx

from tests.control.plantproc import Running, default_plant_copy, fieldtwin_run
from tests.tsx.test_plc_watchdog import nested_jumps, nested_whiles

ANSWER_S = 5.0
WATCH_S = 2.0  # how long the poller watches the plant in its fault
WORST_GAP_S = 1.0
STOP_S = 2.0
FAULT_WITHIN_S = 10.0

# both kinds of loop: backward JUMPs in SR0..SR6 and WHILEs in SR10..SR16
SPIN = nested_jumps() + "".join(
    line.replace("SR", "SR1", 1) if line.startswith("%SR") else line.replace("CALL SR", "CALL SR1")
    for line in nested_whiles().split("\n", 2)[2].splitlines(keepends=True)
)
SPIN = SPIN.replace("%PRE\n!CALL SR0\n", "%PRE\n!CALL SR0\n!CALL SR10\n", 1)


class Poller:
    """pymodbus, reading TES 2's first register over and over; the worst gap."""

    def __init__(self, port: int) -> None:
        from pymodbus.client import ModbusTcpClient

        self.client = ModbusTcpClient("127.0.0.1", port=port, timeout=1, retries=0)
        self.answers: list[float] = []
        self.failures = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> Poller:
        assert self.client.connect()  # type: ignore[no-untyped-call]
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(5)
        self.client.close()  # type: ignore[no-untyped-call]

    def _run(self) -> None:
        from pymodbus.exceptions import ModbusException

        while not self._stop.is_set():
            try:
                reply = self.client.read_holding_registers(0, count=1, device_id=2)
            except ModbusException:
                self.failures += 1
                continue
            if reply.isError():
                self.failures += 1
            else:
                self.answers.append(time.monotonic())
            time.sleep(0.01)

    @property
    def worst_gap(self) -> float:
        return max((b - a for a, b in pairwise(self.answers)), default=1e9)


def _in_fault(api: httpx.Client) -> dict[str, object]:
    deadline = time.monotonic() + FAULT_WITHIN_S
    while True:
        plc = api.get("/plant").json()["plc"]
        if plc["mode"] == "FAULT" or time.monotonic() > deadline:
            assert isinstance(plc, dict)
            return plc
        time.sleep(0.05)


def _faulted_yet_serving(running: Running, api: httpx.Client) -> None:
    with Poller(running.modbus_port) as poller:
        plc = _in_fault(api)
        assert plc["mode"] == "FAULT", plc
        fault = str(plc["fault"])
        assert fault.startswith("watchdog: master task exceeded 150000 operations"), fault
        time.sleep(WATCH_S)
        state = api.get("/dashboard/state").json()["plc"]
        sy11 = api.post("/console", json={"line": "read SY11"}).json()
    assert state["mode"] == "FAULT" and state["fault"] == fault and not state["running"]
    assert sy11 == {"lines": ["SY11 = 1"], "error": None}
    assert poller.failures == 0 and len(poller.answers) > 20
    assert poller.worst_gap <= WORST_GAP_S, poller.worst_gap


def _sigterm_ends_it(running: Running) -> None:
    started = time.monotonic()
    running.proc.send_signal(signal.SIGTERM)
    running.proc.wait(timeout=STOP_S + 3)
    assert time.monotonic() - started <= STOP_S
    assert running.proc.returncode == 0


def test_a_program_looping_forever_from_the_plant_file(tmp_path: Path) -> None:
    plant = default_plant_copy(tmp_path)
    (tmp_path / "spin.pl7").write_text(SPIN)
    plant.write_text(plant.read_text().replace('"default.pl7"', '"spin.pl7"'))  # its program
    with fieldtwin_run(plant) as running:
        with httpx.Client(base_url=running.url, timeout=ANSWER_S) as api:
            _faulted_yet_serving(running, api)
        _sigterm_ends_it(running)


def test_a_program_looping_forever_loaded_through_the_api(tmp_path: Path) -> None:
    with fieldtwin_run(default_plant_copy(tmp_path)) as running:
        with httpx.Client(base_url=running.url, timeout=ANSWER_S) as api:
            assert api.get("/plant").json()["plc"] == {"mode": "RUN", "fault": None}
            answer = api.post("/console", json={"line": "prog load -", "text": SPIN}).json()
            assert answer["error"] is None and answer["lines"][0].startswith("loaded"), answer
            _faulted_yet_serving(running, api)
            # the way back: the manual's program again, then RUN
            refused = api.post("/console", json={"line": "plc run"}).json()
            assert "plc cold" in str(refused["error"])
            assert api.post("/console", json={"line": "plc cold"}).json()["error"] is None
            assert _in_fault(api)["mode"] == "FAULT"  # the same program trips again
            fixed = api.post("/console", json={"line": "prog load -", "text": "!INC W0\n"})
            assert fixed.json()["error"] is None
            assert api.get("/plant").json()["plc"] == {"mode": "RUN", "fault": None}
        _sigterm_ends_it(running)
