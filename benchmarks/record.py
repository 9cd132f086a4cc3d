"""Recording size and replay speed: the default plant under a 10 Hz Modbus TCP poll.

A master polls the default plant every 100 ms of simulated time (holding registers of
TES 1, input registers of TES 2) over a real loopback connection, the plant recording
(``plant.record``) and running as fast as it can (``speed=None``).  Printed:

* bytes per simulated hour of the recording (measured over the simulated span, scaled);
* how fast the recording ran, and how fast ``fieldtwin.replay.replay`` replays it,
  in simulated seconds per wall second (x1 = real time).

Run:  .venv/bin/python benchmarks/record.py [simulated_seconds]   (default 120)
"""

from __future__ import annotations

import contextlib
import re
import socket
import struct
import sys
import tempfile
import time
from importlib import resources
from pathlib import Path

from fieldtwin.clock import MS, S, SimClock
from fieldtwin.plant import build_plant, read_plant
from fieldtwin.replay import replay
from fieldtwin.runtime.runner import Runner

POLL_US = 100 * MS  # 10 Hz


def _request(sock: socket.socket, transaction: int, unit: int, function: int) -> None:
    pdu = struct.pack(">BHH", function, 0, 2 if function == 3 else 4)
    sock.sendall(struct.pack(">HHHB", transaction, 0, len(pdu) + 1, unit) + pdu)


def _answered(sock: socket.socket, buffer: bytearray) -> bool:
    with contextlib.suppress(BlockingIOError):
        buffer += sock.recv(4096)
    return len(buffer) >= 6 and len(buffer) >= 6 + buffer[5]


def record(directory: Path, seconds: float) -> tuple[Path, float]:
    text = resources.files("fieldtwin").joinpath("plants", "default.toml").read_text("utf-8")
    plant_path = directory / "default.toml"
    plant_path.write_text(re.sub(r"127\.0\.0\.1:5020", "127.0.0.1:0", text), "utf-8")
    runner = Runner(SimClock(), speed=None)
    plant = build_plant(read_plant(plant_path), runner=runner, speed=None)
    path = directory / "default.ftrec"
    plant.record(path, runner)
    started = time.perf_counter()
    try:
        line = plant.start_endpoints(runner)[0]
        port = int(line.split()[2].rsplit(":", 1)[1])
        sock = socket.create_connection(("127.0.0.1", port), timeout=2)
        transaction = 0
        try:
            end = round(seconds * S)
            while runner.clock.now < end:
                target = runner.clock.now + POLL_US
                for unit, function in ((1, 3), (2, 4)):
                    transaction = (transaction + 1) & 0xFFFF
                    sock.setblocking(True)
                    _request(sock, transaction, unit, function)
                    sock.setblocking(False)
                    buffer = bytearray()
                    runner.run_until(lambda b=buffer: _answered(sock, b), 50 * MS)  # type: ignore[misc]
                runner.run_to(max(target, runner.clock.now))
        finally:
            sock.close()
    finally:
        plant.close()
    return path, time.perf_counter() - started


def main() -> None:
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 120.0
    with tempfile.TemporaryDirectory() as tmp:
        path, wall = record(Path(tmp), seconds)
        size = path.stat().st_size
        outcome = replay(path)
        assert outcome.identical, outcome.difference
    per_hour = size * 3600 / seconds
    print(f"default plant, 10 Hz Modbus TCP poll, {seconds:g} simulated s")
    print(f"recording: {size} bytes = {per_hour / 1e6:.2f} MB per simulated hour")
    print(f"  ({outcome.inputs} inputs, {outcome.expected} outputs)")
    print(f"recorded at x{seconds / wall:.1f} real time (fast mode)")
    print(f"replayed at x{outcome.speed:.1f} real time ({outcome.wall_s:.2f} s wall), identical")


if __name__ == "__main__":
    main()
