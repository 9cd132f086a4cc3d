"""Issue 20: the simulation can always be reached and stopped (a real `fieldtwin run`).

Each test keeps a Modbus TCP poller (a raw socket) running against the default
plant's TES endpoint beside what it does to the clock; every wait is bounded.
"""

from __future__ import annotations

import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from itertools import pairwise
from pathlib import Path

import httpx

from fieldtwin.runtime.pace import MAX_SPEED, MIN_SPEED
from tests.control.plantproc import ROOT, Running, default_plant_copy, fieldtwin_run

ANSWER_S = 2.0  # an API answer that takes longer is a failure
POLL_FOR_S = 3.0  # how long the poller watches the plant at the top speed
WORST_GAP_S = 1.0
STOP_S = 2.0  # SIGTERM to exit, for a plant that is running
LAUNCHES = 50
STOP_ANY_S = 3.0  # SIGTERM to exit, at any moment from the launch on


class Poller:
    """Reads the TES 2 status word over and over; the worst gap between two answers."""

    def __init__(self, port: int) -> None:
        self.port = port
        self.answers: list[float] = []
        self.failures = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> Poller:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(5)

    def _run(self) -> None:
        with socket.create_connection(("127.0.0.1", self.port), timeout=1) as sock:
            tid = 0
            while not self._stop.is_set():
                tid = (tid + 1) & 0xFFFF
                sock.sendall(struct.pack(">HHHBBHH", tid, 0, 6, 2, 3, 0x000, 1))
                try:
                    reply = sock.recv(260)
                except TimeoutError:
                    self.failures += 1
                    continue
                except OSError:  # the plant has gone
                    return
                if len(reply) >= 9 and reply[7] == 3:
                    self.answers.append(time.monotonic())
                else:
                    self.failures += 1
                time.sleep(0.01)

    @property
    def worst_gap(self) -> float:
        times = self.answers
        return max((b - a for a, b in pairwise(times)), default=1e9)


@contextmanager
def _plant(tmp: Path, *extra: str) -> Iterator[Running]:
    with fieldtwin_run(default_plant_copy(tmp), *extra) as running:
        yield running


def _sigterm_ends_it(running: Running) -> None:
    started = time.monotonic()
    running.proc.send_signal(signal.SIGTERM)
    running.proc.wait(timeout=STOP_S + 3)
    assert time.monotonic() - started <= STOP_S
    assert running.proc.returncode == 0


def _watch_at_top_speed(running: Running, api: httpx.Client) -> None:
    with Poller(running.modbus_port) as poller:
        time.sleep(POLL_FOR_S)
        clock = api.get("/clock").json()
    assert len(poller.answers) > 10, poller.failures
    assert poller.worst_gap <= WORST_GAP_S, poller.worst_gap
    assert clock["speed"] == MAX_SPEED
    assert clock["speed_reached"] is not None and clock["speed_reached"] > 1
    assert isinstance(clock["speed_kept"], bool)


def test_the_top_speed_through_the_api_keeps_modbus_the_api_and_sigterm(tmp_path: Path) -> None:
    with _plant(tmp_path) as running:
        with httpx.Client(base_url=running.url, timeout=ANSWER_S) as api:
            low = api.put("/clock/speed", json={"speed": 1e-300})
            assert low.status_code == 422 and f"{MIN_SPEED:g}" in low.text, low.text
            assert api.put("/clock/speed", json={"speed": MAX_SPEED * 10}).status_code == 422
            assert api.put("/clock/speed", json={"speed": MAX_SPEED}).status_code == 200
            _watch_at_top_speed(running, api)
            assert api.put("/clock/speed", json={"speed": 1}).json()["speed"] == 1
        _sigterm_ends_it(running)


def test_the_top_speed_on_the_command_line_keeps_modbus_the_api_and_sigterm(
    tmp_path: Path,
) -> None:
    with _plant(tmp_path, "--speed", f"{MAX_SPEED:g}") as running:
        with httpx.Client(base_url=running.url, timeout=ANSWER_S) as api:
            _watch_at_top_speed(running, api)
        _sigterm_ends_it(running)


def test_a_speed_out_of_bounds_on_the_command_line_names_the_range() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "fieldtwin", "run", "--speed", "1e-300"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
    )
    assert done.returncode == 2
    assert f"from {MIN_SPEED:g} to {MAX_SPEED:g}" in done.stderr


def test_long_clock_commands_hold_nothing_and_pause_takes_effect_at_once(tmp_path: Path) -> None:
    with _plant(tmp_path) as running:
        with (
            Poller(running.modbus_port) as poller,
            httpx.Client(base_url=running.url, timeout=ANSWER_S) as api,
        ):
            started = api.post("/clock/run-until", json={"t_s": 1e9}).json()
            assert started["mode"] == "run-until" and started["until_s"] == 1e9
            assert api.get("/clock").json()["mode"] == "run-until"
            time.sleep(1.0)  # the mode runs; Modbus is served all along
            assert len(poller.answers) > 5 and poller.failures == 0
            assert poller.worst_gap <= WORST_GAP_S
            # (held time: Modbus waits, by design)
            paused = api.post("/clock/pause", json={}).json()
            assert paused["paused"] is True and paused["mode"] is None
            time.sleep(0.3)
            assert api.get("/clock").json()["t_us"] == paused["t_us"]  # held at once
            step = api.post("/clock/step", json={"ms": 86_400_000}).json()
            assert step["mode"] == "step"
            assert api.put("/clock/speed", json={"speed": 2}).json()["mode"] == "step"
            assert api.post("/clock/pause", json={}).json()["mode"] is None
            broke = api.post("/plc/power-break", json={"seconds": 3600}).json()
            assert broke["mode"] == "power-break" and broke["power"] == "off"
            assert api.get("/plant").status_code == 200
            held = api.post("/clock/pause", json={}).json()
            assert held["mode"] is None  # the break is over: the power is back
            short = api.post("/clock/step", json={"ms": 100, "wait": True, "wait_s": 5})
            assert short.json()["t_us"] == held["t_us"] + 100_000
            assert short.json()["mode"] is None and short.json()["cut"] is False
        _sigterm_ends_it(running)


def _launch_and_stop(plant: Path, delay: float) -> float | None:
    """Start `fieldtwin run`, SIGTERM it ``delay`` s later; seconds until it is gone
    (None: it was still there after STOP_ANY_S, and was killed)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldtwin", "run", str(plant), "--no-live", "--control-port", "0"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        cwd=ROOT,
    )
    time.sleep(delay)
    sent = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout=STOP_ANY_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=10)
        return None
    return time.monotonic() - sent


def test_sigterm_at_any_moment_from_the_launch_ends_the_process(tmp_path: Path) -> None:
    """50 launches, SIGTERM 0 to 2 s after each start, four at a time (bounded wall time)."""
    delays = [2.0 * i / (LAUNCHES - 1) for i in range(LAUNCHES)]
    with ThreadPoolExecutor(max_workers=4) as pool:
        plant = default_plant_copy(tmp_path)
        gone = list(pool.map(lambda delay: _launch_and_stop(plant, delay), delays))
    late = [d for d, g in zip(delays, gone, strict=True) if g is None]
    assert not late, f"still running {STOP_ANY_S} s after SIGTERM sent at {late}"


def test_a_console_advance_through_the_api_holds_nothing(tmp_path: Path) -> None:
    """`advance` and `power break` sent as console lines are runner modes too: the line
    is answered at its end (or at wait_s with the mode running on), and pause, speed and
    reads are served meanwhile."""
    with _plant(tmp_path) as running:
        with (
            Poller(running.modbus_port) as poller,
            httpx.Client(base_url=running.url, timeout=ANSWER_S) as api,
        ):
            answer = api.post("/console", json={"line": "advance 100000", "wait_s": 0.3}).json()
            assert answer["error"] is None
            assert answer["lines"][0].startswith("advancing to t = 1000"), answer
            assert api.get("/clock").json()["mode"] == "advance"
            assert api.put("/clock/speed", json={"speed": 2}).json()["mode"] == "advance"
            paused = api.post("/clock/pause", json={}).json()
            assert paused["mode"] is None and paused["paused"] is True
            assert len(poller.answers) > 5 and poller.worst_gap <= WORST_GAP_S
            done = api.post("/console", json={"line": "advance 250ms", "wait_s": 5}).json()
            assert done == {"lines": [f"t = {paused['t_s'] + 0.25:.3f} s"], "error": None}
            broke = api.post("/console", json={"line": "power break 3600", "wait_s": 0.3}).json()
            assert broke["lines"][0].startswith("power off until"), broke
            assert api.get("/clock").json()["mode"] == "power-break"
            assert api.post("/clock/pause", json={}).json()["mode"] is None
            short = api.post("/console", json={"line": "power break 0.1", "wait_s": 5}).json()
            assert short["lines"][0].startswith("power back  t = "), short
        _sigterm_ends_it(running)
