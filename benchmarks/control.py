"""The control API's figures: requests/s, event-stream events/s, Modbus TCP with and without
a subscriber (issue 11).

* API: a closed loop of ``GET /clock`` (one command through the runner's inbox each)
  and of ``PUT .../inputs`` against a real ``fieldtwin run`` (default plant, x1);
* event stream: events published on an EventBus as fast as one thread can, carried
  by the real WebSocket endpoint (uvicorn in a thread) to a websockets client:
  received per second, and how many a bounded queue dropped;
* Modbus TCP: a pymodbus master reading 10 holding registers of TES 1 in a closed
  loop, without and then with a subscriber of every event attached (ratio printed).

Run:  .venv/bin/python benchmarks/control.py [seconds per measure]
"""

from __future__ import annotations

import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.control.plantproc import default_plant_copy, fieldtwin_run  # noqa: E402


def api_rate(url: str, seconds: float) -> tuple[float, float]:
    import httpx

    with httpx.Client(base_url=url, timeout=10) as http:
        rates = []
        for method, path, body in (
            ("GET", "/clock", None),
            ("PUT", "/devices/tes1/inputs/3", {"value": True}),
        ):
            count, end = 0, time.perf_counter() + seconds
            start = time.perf_counter()
            while time.perf_counter() < end:
                assert http.request(method, path, json=body).status_code == 200
                count += 1
            rates.append(count / (time.perf_counter() - start))
    return rates[0], rates[1]


def stream_rate(seconds: float) -> tuple[float, int, int]:
    """Events/s through the real WebSocket endpoint (no plant thread needed)."""
    from fieldtwin.control.resources import Control
    from fieldtwin.control.server import ControlServer, bind_control
    from fieldtwin.plant import build_plant, read_plant
    from fieldtwin.runtime.events import EventBus
    from fieldtwin.runtime.inbox import Inbox
    from fieldtwin.runtime.runner import Runner

    plant = build_plant(read_plant(None))
    runner = Runner(plant.clock, None)
    bus = EventBus()
    inbox = Inbox()
    server = ControlServer(
        Control(plant, runner, bus), inbox, bind_control("127.0.0.1", 0, fallback=False), None
    )
    url = server.start()
    from fieldtwin.client import Client

    received = [0]
    client = Client(url)
    events = client.events(queue=10_000, timeout_s=1.0)
    stop = threading.Event()

    def publish() -> None:
        n = 0
        while not stop.is_set():
            bus.publish(n, "modbus", "bench", {"n": n, "function": 3})
            n += 1
            if n % 1000 == 0:
                time.sleep(0)

    publisher = threading.Thread(target=publish, daemon=True)
    start = time.perf_counter()
    publisher.start()
    dropped = 0
    for event in events:
        if event["kind"] == "dropped":
            dropped += int(event["count"])
        else:
            received[0] += 1
        if time.perf_counter() - start > seconds:
            break
    elapsed = time.perf_counter() - start
    stop.set()
    publisher.join(5)
    published = bus.published
    server.close()
    inbox.close()
    client.close()
    return received[0] / elapsed, dropped, published


def modbus_rate(port: int, seconds: float) -> float:
    from pymodbus.client import ModbusTcpClient

    client = ModbusTcpClient("127.0.0.1", port=port, timeout=2, retries=0)
    assert client.connect()
    count, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        assert not client.read_holding_registers(0, count=10, device_id=1).isError()
        count += 1
    client.close()
    return count / (time.perf_counter() - start)


def with_subscriber(url: str, port: int, seconds: float) -> tuple[float, int]:
    from fieldtwin.client import Client

    seen = [0]
    stop = threading.Event()
    client = Client(url)
    events = client.events(timeout_s=0.5)

    def read() -> None:
        for _ in events:
            seen[0] += 1
            if stop.is_set():
                break

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    rate = modbus_rate(port, seconds)
    stop.set()
    reader.join(5)
    client.close()
    return rate, seen[0]


def main() -> None:
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 3.0
    with tempfile.TemporaryDirectory() as tmp, fieldtwin_run(default_plant_copy(Path(tmp))) as run:
        clock, inputs = api_rate(run.url, seconds)
        print(f"API GET /clock:                      {clock:8.0f} requests/s")
        print(f"API PUT /devices/tes1/inputs/3:      {inputs:8.0f} requests/s")
        # alternated (bare, watched, bare): the machine's load drifts during a run
        before = modbus_rate(run.modbus_port, seconds)
        watched, seen = with_subscriber(run.url, run.modbus_port, seconds)
        bare = (before + modbus_rate(run.modbus_port, seconds)) / 2
        print(f"Modbus TCP FC03 x10, no subscriber:  {bare:8.0f} requests/s")
        print(
            f"Modbus TCP FC03 x10, one subscriber: {watched:8.0f} requests/s"
            f"  (ratio {watched / bare:.2f}; {seen} events seen)"
        )
    rate, dropped, published = stream_rate(seconds)
    print(
        f"event stream (WebSocket):            {rate:8.0f} events/s"
        f"  ({published} published, {dropped} dropped by the bounded queue)"
    )


if __name__ == "__main__":
    main()
