"""The control API's figures: requests/s, event-stream events/s, Modbus TCP with and without
a subscriber (issue 11), and the API against references (issue 26).

* API against references: ``GET /clock`` (answered from the snapshot the simulation
  published) and ``PUT .../inputs/3`` (a command through the runner's inbox) on a real
  ``fieldtwin run`` (default plant, x1), each beside the same request on a reference
  started here in its own process: a bare FastAPI + uvicorn app answering the same
  bodies (target: GET >= 0.8x bare), and pymodbus's simulator REST API setting one
  register (``POST /restapi/registers``; target: PUT >= 1x; it needs aiohttp, the
  ``pymodbus[simulator]`` extra: skipped without).  The load is wrk (Debian's ``wrk``)
  when on PATH, else as many client processes as connections (httpx, closed loop);
  each figure is the median of ROUNDS rounds alternated between the servers (the
  machine's load drifts during a run), beside each server's CPU time per request
  (its process's user + system time over the requests wrk counted: Linux), which a
  machine shared with other jobs disturbs far less than requests per second; the
  load average is printed before and after.  Every uvicorn server takes uvicorn's
  default HTTP parser and loop (httptools and uvloop when installed, else h11 and
  asyncio's: printed); pymodbus's REST API runs on asyncio's loop, its default;
* a closed loop of one ``httpx`` client (one connection) on the same two requests;
* event stream: events published on an EventBus as fast as one thread can, carried
  by the real WebSocket endpoint (uvicorn in a thread) to a websockets client:
  received per second, and how many a bounded queue dropped;
* Modbus TCP: a pymodbus master reading 10 holding registers of TES 1 in a closed
  loop, without and then with a subscriber of every event attached (ratio printed).

Run:  .venv/bin/python benchmarks/control.py [seconds per measure] [--references]
(``--references``: only the API against the references.)
"""

from __future__ import annotations

import importlib.util
import json
import multiprocessing
import os
import re
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from pydantic import BaseModel

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.control.plantproc import default_plant_copy, fieldtwin_run  # noqa: E402

CONNECTIONS = 8  # the load's connections (wrk: on one thread; else one process each)
ROUNDS = 3
GET_TARGET, PUT_TARGET = 0.8, 1.0
INPUT_BODY = {"value": True}
START_S = 30.0


# --- the references, each served in a process of its own ------------------------------


class BareBody(BaseModel):
    value: bool | int | float | str | None = None


def serve_bare(port: int) -> None:
    """A bare FastAPI app on uvicorn: the same paths and bodies, no plant behind."""
    import uvicorn
    from fastapi import FastAPI

    app = FastAPI()
    state = {"t_s": 1.0, "t_us": 1_000_000, "paused": False, "speed": 1.0, "mode": None}

    @app.get("/clock")
    async def clock() -> dict[str, object]:
        return {**state, "until_s": None, "speed_reached": 1.0, "speed_kept": True}

    @app.put("/devices/{ident}/inputs/{name}")
    async def put_input(ident: str, name: str, body: BareBody) -> dict[str, object]:
        return {"device": ident, "input": name, "value": body.value}

    uvicorn.run(app, host="127.0.0.1", port=port, log_level="warning", access_log=False)


def serve_pymodbus(http_port: int, modbus_port: int, tmp: str) -> None:
    """pymodbus's simulator: its Modbus TCP server and its REST API (aiohttp)."""
    import asyncio

    import pymodbus.server.simulator as simulator
    from pymodbus.server import ModbusSimulatorServer

    setup = json.loads((Path(simulator.__file__).parent / "setup.json").read_text())
    setup["server_list"]["server"].update(host="127.0.0.1", port=modbus_port)
    path = Path(tmp) / "setup.json"
    path.write_text(json.dumps(setup))

    async def run() -> None:
        server = ModbusSimulatorServer(
            http_host="127.0.0.1",
            http_port=http_port,
            json_file=str(path),
            log_file=str(Path(tmp) / "server.log"),
        )
        await server.run_forever()

    asyncio.run(run())


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


@contextmanager
def served(args: list[str], port: int) -> Iterator[tuple[str, int]]:
    """``benchmarks/control.py ARGS`` in a process of its own, until its port answers:
    its URL and process id."""
    proc = subprocess.Popen(
        [sys.executable, __file__, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    try:
        deadline = time.monotonic() + START_S
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    err = proc.stderr.read().decode() if proc.stderr else ""
                    raise RuntimeError(f"{args[0]} did not start: {err[-2000:]}") from None
                time.sleep(0.05)
        yield f"http://127.0.0.1:{port}", proc.pid
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


# --- the load ---------------------------------------------------------------------------


def cpu_s(pid: int) -> float | None:
    """A process's user + system CPU seconds so far (Linux's /proc); None elsewhere."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            fields = stat.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def http_parser() -> str:
    """The HTTP implementation uvicorn's default ("auto") takes here."""
    return "httptools" if importlib.util.find_spec("httptools") else "h11"


def event_loop() -> str:
    """The event loop uvicorn's default ("auto") takes here (pymodbus's REST API runs on
    asyncio's own, its default)."""
    return "uvloop" if importlib.util.find_spec("uvloop") else "asyncio"


def wrk_rate(url: str, method: str, body: object, seconds: float) -> tuple[float, int]:
    """Requests/s by wrk, and how many requests (every answer must be a 2xx: asserted)."""
    with tempfile.NamedTemporaryFile("w", suffix=".lua", delete=False) as script:
        script.write(f'wrk.method = "{method}"\n')
        if body is not None:
            script.write(f"wrk.body = {json.dumps(json.dumps(body))}\n")
            script.write('wrk.headers["Content-Type"] = "application/json"\n')
    try:
        done = subprocess.run(
            [
                "wrk",
                "-t1",
                f"-c{CONNECTIONS}",
                f"-d{max(1, round(seconds))}s",
                "-s",
                script.name,
                url,
            ],
            capture_output=True,
            text=True,
            timeout=seconds + 30,
            check=True,
        )
    finally:
        os.unlink(script.name)
    assert "Non-2xx" not in done.stdout and "Socket errors" not in done.stdout, done.stdout
    found = re.search(r"Requests/sec:\s+([\d.]+)", done.stdout)
    count = re.search(r"(\d+) requests in", done.stdout)
    assert found and count, done.stdout
    return float(found.group(1)), int(count.group(1))


def _client_loop(url: str, method: str, body: object, seconds: float, out: object) -> None:
    import httpx

    count, end = 0, time.perf_counter() + seconds
    with httpx.Client(timeout=10) as http:
        while time.perf_counter() < end:
            reply = http.request(method, url, json=body)
            assert reply.status_code < 300, reply.text
            count += 1
    out.put(count)  # type: ignore[attr-defined]


def processes_rate(url: str, method: str, body: object, seconds: float) -> tuple[float, int]:
    """Requests/s by CONNECTIONS client processes, each a closed loop on its connection."""
    context = multiprocessing.get_context("spawn")
    counts = context.Queue()
    workers = [
        context.Process(target=_client_loop, args=(url, method, body, seconds, counts))
        for _ in range(CONNECTIONS)
    ]
    for worker in workers:
        worker.start()
    total = sum(counts.get(timeout=seconds + 60) for _ in workers)
    for worker in workers:
        worker.join(10)
    return total / seconds, total


def load_rate(
    server: tuple[str, int], path: str, method: str, body: object, seconds: float
) -> tuple[float, float | None]:
    """Requests/s on ``path`` of ``server`` (its URL and process), and the server's CPU
    microseconds per request (None where the system does not say)."""
    url, pid = server
    before = cpu_s(pid)
    if shutil.which("wrk"):
        rate, count = wrk_rate(url + path, method, body, seconds)
    else:
        rate, count = processes_rate(url + path, method, body, seconds)
    after = cpu_s(pid)
    if before is None or after is None or not count:
        return rate, None
    return rate, (after - before) / count * 1e6


def register_body() -> dict[str, object]:
    """pymodbus's REST API: set register 1 (a value it keeps), as its web page does."""
    return {"submit": "Set", "register": 1, "value": 7, "range_start": 1, "range_stop": 1}


def against_references(server: tuple[str, int], seconds: float) -> None:
    """Our GET /clock and PUT input against the bare app and pymodbus's REST API
    (``server``: the plant's URL and process id)."""
    tool = "wrk" if shutil.which("wrk") else f"{CONNECTIONS} client processes"
    print(
        f"load: {tool}, {CONNECTIONS} connections; median of {ROUNDS} rounds of {seconds:g} s,"
        f" alternated; uvicorn's HTTP parser: {http_parser()}, its loop: {event_loop()}"
    )
    print(f"load average before: {_load()}")
    bare_port = free_port()
    have_sim = importlib.util.find_spec("aiohttp") is not None
    rates: dict[str, list[float]] = {}
    cpus: dict[str, list[float]] = {}

    def measure(name: str, on: tuple[str, int], path: str, method: str, body: object) -> None:
        rate, cpu = load_rate(on, path, method, body, seconds)
        rates.setdefault(name, []).append(rate)
        if cpu is not None:
            cpus.setdefault(name, []).append(cpu)

    put_path = "/devices/tes1/inputs/3"
    sim_port = free_port()
    with (
        served(["--serve-bare", str(bare_port)], bare_port) as bare,
        tempfile.TemporaryDirectory() as tmp,
    ):
        sim_args = ["--serve-pymodbus", str(sim_port), str(free_port()), tmp]
        with served(sim_args, sim_port) if have_sim else _nothing() as sim:
            for _ in range(ROUNDS):
                measure("get", server, "/clock", "GET", None)
                measure("get bare", bare, "/clock", "GET", None)
                measure("put", server, put_path, "PUT", INPUT_BODY)
                measure("put bare", bare, put_path, "PUT", INPUT_BODY)
                if sim[0]:
                    measure("put sim", sim, "/restapi/registers", "POST", register_body())
    rate = {name: statistics.median(each) for name, each in rates.items()}
    cpu = {name: statistics.median(each) for name, each in cpus.items()}

    def line(label: str, name: str) -> None:
        used = f"  {cpu[name]:6.0f} us CPU/request" if name in cpu else ""
        print(f"{label:37s}{rate[name]:8.0f} requests/s{used}")

    def ratio(ours: str, theirs: str, target: float) -> None:
        throughput = rate[ours] / rate[theirs]
        said = f"  ratio {throughput:.2f} ({_verdict(throughput, target)})"
        if ours in cpu and theirs in cpu:
            said += f"; CPU per request ratio {cpu[theirs] / cpu[ours]:.2f}"
        print(said)

    line("GET /clock, fieldtwin (snapshot):", "get")
    line("GET /clock, bare FastAPI + uvicorn:", "get bare")
    ratio("get", "get bare", GET_TARGET)
    line("PUT input, fieldtwin (inbox):", "put")
    line("PUT input, bare FastAPI + uvicorn:", "put bare")
    if "put sim" in rate:
        line("POST /restapi/registers, pymodbus:", "put sim")
        ratio("put", "put sim", PUT_TARGET)
    else:
        print("pymodbus simulator REST API: skipped (needs aiohttp: 'pymodbus[simulator]')")
    print(f"load average after: {_load()}")


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def _verdict(ratio: float, target: float) -> str:
    return f"target >= {target}: {'met' if ratio >= target else 'NOT met'}"


@contextmanager
def _nothing() -> Iterator[tuple[str, int]]:
    yield "", 0


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
    if len(sys.argv) > 1 and sys.argv[1] == "--serve-bare":
        serve_bare(int(sys.argv[2]))
        return
    if len(sys.argv) > 1 and sys.argv[1] == "--serve-pymodbus":
        serve_pymodbus(int(sys.argv[2]), int(sys.argv[3]), sys.argv[4])
        return
    words = [word for word in sys.argv[1:] if word != "--references"]
    only_references = len(words) < len(sys.argv) - 1
    seconds = float(words[0]) if words else 3.0
    with tempfile.TemporaryDirectory() as tmp, fieldtwin_run(default_plant_copy(Path(tmp))) as run:
        against_references((run.url, run.proc.pid), seconds)
        if only_references:
            return
        clock, inputs = api_rate(run.url, seconds)
        print(f"API GET /clock, one connection:      {clock:8.0f} requests/s")
        print(f"API PUT /devices/tes1/inputs/3, one: {inputs:8.0f} requests/s")
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
