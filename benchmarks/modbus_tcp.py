"""Modbus TCP throughput and latency: our server glue against a plain pymodbus server.

Each server runs in its own process; each client connection is its own process
(a raw-socket closed loop: send one MBAP "read 10 holding registers", wait for
the reply, repeat), so neither side shares a GIL with the other.  For 1 and 8
concurrent connections it prints requests per second, p50 and p99 latency, and
the ratio ours / pymodbus.  Bounded: DURATION_S per case.

    .venv/bin/python benchmarks/modbus_tcp.py [--duration 2.0]

With ``--kit DIR`` (the neutral benchmark kit, ../shared/bench on the project's
machine: a C load generator that does not starve the server on two cores) it
runs that kit's compare.py instead, by path (never copied here): pymodbus 3.16,
libmodbus when its anchor is built (``bash DIR/build.sh`` with libmodbus-dev
installed), and fieldtwin serving a TES 32EST at 1 and 8 connections, alternated:
FC03 of words 0..9 (status and inputs: what a SCADA polls first), then FC03 and FC16
of words 37..46.  After the kit's own tables it prints one summary: medians of
requests per second and p99, the server's CPU per request (its CPU time from /proc
over every request it answered, warm-up included) and the ratios against pymodbus
and libmodbus.  It says so when the kit or its mbload binary is absent.

With ``--counts`` it prints the instructions our server process executes per
request (benchmarks/counts.py: perf or callgrind) from 8 connections: the table
device's FC03, and the TES 32EST's FC03 of words 0..9 and FC03 and FC16 of words
37..46; each a fixed workload (``--workload N``: the server, fed by 8 client
processes of N/8 requests each, which are not counted), at two sizes, so that
start-up cancels out.  Then the same from one connection (the table device's FC03 at
37, the TES's FC03 of words 0..9), where each request is one cycle of the runner,
whose inbox is there as in ``fieldtwin run``.  The machine's load does not move these
figures.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.queues import Queue
from pathlib import Path
from typing import Any

from pymodbus.datastore import ModbusDeviceContext, ModbusSequentialDataBlock, ModbusServerContext
from pymodbus.server import StartTcpServer

from fieldtwin.clock import SimClock
from fieldtwin.modbus.mbap import encode_mbap
from fieldtwin.modbus.model import (
    Counter,
    Link,
    ReadWords,
    Request,
    Result,
    SlaveDevice,
    WriteWords,
)
from fieldtwin.modbus.pdu import encode_request
from fieldtwin.runtime.inbox import Inbox
from fieldtwin.runtime.modbus_server import serve_tcp
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.tcp import listen

WORDS = 10
UNIT = 1
READY_TIMEOUT_S = 10.0
REPLY_SIZE = 9 + 2 * WORDS
# --counts: (device, function, first word) of each counted workload: the plain table,
# then a TES 32EST's status and inputs (words 0..9: what a SCADA polls first), its
# counters (37..46: read and written)
COUNTED = (("table", 3, 0), ("tes", 3, 0), ("tes", 3, 37), ("tes", 16, 37))
# --counts at one connection: each request is one runner cycle (its wait, its inbox)
COUNTED_ONE = (("table", 3, 37), ("tes", 3, 0))
# --kit: (first word, functions) of each alternated run of the kit: a TES 32EST's words
# 0..9 (status, memorized, filtered and direct inputs, outputs), then 37..46
KIT_CASES = ((0, (3,)), (37, (3, 16)))


# --- servers (each in its own process) ------------------------------------------


class Table:
    """The static table behind our server: 256 holding words, like pymodbus's datastore."""

    def __init__(self, slave: int) -> None:
        self.slave = slave
        self.words = tuple(range(256))

    def execute(self, request: Request, link: Link, now: int, broadcast: bool) -> Result:
        assert isinstance(request, ReadWords)
        return self.words[request.address : request.address + request.count]

    def count(self, link: Link, counter: Counter, now: int) -> None:
        pass

    def answer_delay(self, link: Link) -> int:
        return 0


def _counted_request(fc: int, address: int) -> tuple[Request, int]:
    """The request of a counted workload and the size of its reply."""
    if fc == 16:
        return WriteWords(address, tuple(range(WORDS))), 12
    return ReadWords(fc, address, WORDS), REPLY_SIZE


def _client_count(port: int, count: int, fc: int = 3, address: int = 0) -> None:
    """A counted workload's client: ``count`` requests, one at a time, then exit."""
    request, size = _counted_request(fc, address)
    frame = encode_request(request)
    with socket.create_connection(("127.0.0.1", port), timeout=60) as sock:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        for tid in range(1, count + 1):
            sock.sendall(encode_mbap(tid, UNIT, frame))
            got = b""
            while len(got) < size:
                chunk = sock.recv(4096)
                if not chunk:
                    raise SystemExit("server closed the connection")
                got += chunk


def workload(kind: str, requests: int, connections: int = 8, fc: int = 3, address: int = 0) -> None:
    """The counted work: our server answering ``requests`` (``fc`` of 10 words at
    ``address``) from ``connections`` client processes (started with exec, so a
    counter does not follow them); the runner takes commands from an inbox, as
    ``fieldtwin run``'s does (none come)."""
    runner, port = _our_server(kind)
    runner.take_commands(Inbox())
    each = requests // connections
    command = [sys.executable, __file__, "--client", str(port), str(each), str(fc), str(address)]
    clients = [subprocess.Popen(command) for _ in range(connections)]
    deadline = time.monotonic() + 1800

    def done(now: int) -> None:
        if all(c.poll() is not None for c in clients) or time.monotonic() > deadline:
            runner.stop()

    runner.run_forever(done, tick_us=20_000)
    if any(c.wait(10) != 0 for c in clients):
        raise SystemExit("a client failed")
    print(f"units {each * connections}")


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def _our_server(kind: str) -> tuple[Runner, int]:
    """Our Modbus TCP server of one device (a table, or a TES 32EST) on a free port."""
    clock = SimClock()
    devices: list[SlaveDevice]
    if kind == "tes":
        from fieldtwin.tes import Tes

        devices = [Tes("32EST", UNIT, clock=clock)]
    else:
        devices = [Table(UNIT)]
    runner = Runner(clock, speed=1.0)
    listener = listen("127.0.0.1", 0)
    serve_tcp(runner, listener, devices)
    return runner, listener.address[1]


def _serve_ours(kind: str, ports: Queue[int]) -> None:
    runner, port = _our_server(kind)
    ports.put(port)
    runner.run_forever()


def _serve_pymodbus(ports: Queue[int]) -> None:
    # pymodbus maps request address 0 to block address 1.
    block = ModbusSequentialDataBlock(1, list(range(256)))  # type: ignore[no-untyped-call]
    context = ModbusServerContext(devices=ModbusDeviceContext(hr=block), single=True)
    port = _free_port()
    ports.put(port)
    StartTcpServer(context=context, address=("127.0.0.1", port))


# --- the client (one process per connection) ------------------------------------


def _client(port: int, duration: float, start_at: float, out: Queue[list[float]]) -> None:
    request = encode_request(ReadWords(3, 0, WORDS))
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    latencies: list[float] = []
    while time.time() < start_at:
        time.sleep(0.001)
    end = time.perf_counter() + duration
    tid = 0
    while (t0 := time.perf_counter()) < end:
        tid = (tid + 1) & 0xFFFF
        sock.sendall(encode_mbap(tid, UNIT, request))
        got = b""
        while len(got) < REPLY_SIZE:
            chunk = sock.recv(4096)
            if not chunk:
                raise SystemExit("server closed the connection")
            got += chunk
        assert got[:2] == tid.to_bytes(2, "big"), got.hex()
        latencies.append(time.perf_counter() - t0)
    sock.close()
    out.put(latencies)


@dataclass(frozen=True)
class Figures:
    rps: float
    p50_ms: float
    p99_ms: float


def _measure(port: int, connections: int, duration: float) -> Figures:
    out: Queue[list[float]] = mp.Queue()
    start_at = time.time() + 0.5
    procs = [
        mp.Process(target=_client, args=(port, duration, start_at, out)) for _ in range(connections)
    ]
    for proc in procs:
        proc.start()
    samples = [out.get(timeout=duration + 30) for _ in procs]
    for proc in procs:
        proc.join(10)
    merged = sorted(x for s in samples for x in s)
    if not merged:
        raise SystemExit("no request completed")
    p99 = merged[min(len(merged) - 1, int(len(merged) * 0.99))]
    return Figures(len(merged) / duration, statistics.median(merged) * 1e3, p99 * 1e3)


def _with_server(target: Callable[..., None], args: tuple[object, ...]) -> mp.Process:
    return mp.Process(target=target, args=args, daemon=True)


def _run_case(
    name: str, make: Callable[[Queue[int]], mp.Process], duration: float
) -> dict[int, Figures]:
    ports: Queue[int] = mp.Queue()
    server = make(ports)
    server.start()
    try:
        port = ports.get(timeout=READY_TIMEOUT_S)
        time.sleep(0.3)  # let the server reach its accept loop
        return {n: _measure(port, n, duration) for n in (1, 8)}
    finally:
        server.terminate()
        server.join(5)
        print(f"  done: {name}", file=sys.stderr)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=2.0, help="seconds per case")
    parser.add_argument("--kit", help="the shared benchmark kit's directory (compare.py, mbload)")
    parser.add_argument("--reps", type=int, default=3, help="with --kit: repetitions")
    parser.add_argument("--counts", action="store_true", help="instructions per request")
    parser.add_argument("--workload", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--device", default="table", help=argparse.SUPPRESS)
    parser.add_argument("--fc", type=int, default=3, help=argparse.SUPPRESS)
    parser.add_argument("--address", type=int, default=0, help=argparse.SUPPRESS)
    parser.add_argument("--conns", type=int, default=8, help=argparse.SUPPRESS)
    parser.add_argument("--client", nargs=4, type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.client is not None:
        _client_count(*args.client)
        return
    if args.workload is not None:
        workload(args.device, args.workload, args.conns, fc=args.fc, address=args.address)
        return
    if args.counts:
        from counts import per_unit

        for conns, cases in ((8, COUNTED), (1, COUNTED_ONE)):
            for device, fc, address in cases:
                extra = ("--device", device, "--fc", str(fc), "--address", str(address))
                extra += ("--conns", str(conns))
                result = per_unit(__file__, 400, 2000, "request", *extra)
                what = f"FC{fc:02d} x {WORDS} at {address}"
                print(
                    f"fieldtwin server ({device}), {conns} connection{'s' * (conns > 1)},"
                    f" {what}: {result}",
                    flush=True,
                )
        return
    if args.kit is not None:
        raise SystemExit(_kit(Path(args.kit), args.duration, args.reps))
    mp.set_start_method("spawn", force=True)
    cases: dict[str, Callable[[Queue[int]], mp.Process]] = {
        "fieldtwin (table device)": lambda q: _with_server(_serve_ours, ("table", q)),
    }
    try:
        from fieldtwin.tes import Tes  # noqa: F401

        cases["fieldtwin (TES 32EST)"] = lambda q: _with_server(_serve_ours, ("tes", q))
    except ImportError:
        print("fieldtwin.tes.Tes not available: TES case skipped", file=sys.stderr)
    cases["pymodbus 3.16 (static datastore)"] = lambda q: _with_server(_serve_pymodbus, (q,))
    results = {name: _run_case(name, make, args.duration) for name, make in cases.items()}
    _report(results, args.duration)


def _kit(kit: Path, duration: float, reps: int) -> int:
    """Run the kit's compare.py against pymodbus, libmodbus (if built) and fieldtwin."""
    kit = kit.resolve()  # compare.py runs in the kit's directory: a relative path would break
    build = Path(os.environ.get("BENCH_BUILD", "/tmp/fieldtwin-bench"))
    compare, mbload = kit / "compare.py", build / "mbload"
    if not compare.is_file():
        print(f"benchmark kit absent: no {compare}", file=sys.stderr)
        return 1
    if not mbload.is_file():
        print(f"benchmark kit not built: no {mbload} (bash {kit}/build.sh)", file=sys.stderr)
        return 1
    venv = Path(sys.executable).parent
    servers = [
        f"pymodbus={sys.executable} {kit / 'anchor_pymodbus.py'} --port {{port}}",
        f"fieldtwin=env FT={venv / 'fieldtwin'} {kit / 'fieldtwin_server.sh'} tcp {{port}}",
    ]
    anchor = build / "anchor_libmodbus"
    if anchor.is_file():
        servers.insert(1, f"libmodbus={anchor} --port {{port}}")
    else:
        print(f"libmodbus anchor not built ({anchor}): pymodbus only", file=sys.stderr)
    status = 0
    runs: list[dict[str, object]] = []
    for address, functions in KIT_CASES:
        outdir = tempfile.mkdtemp(prefix="modbus_tcp_")
        command = [
            sys.executable, str(compare), "--mode", "tcp", "--reps", str(reps), "--conns", "1,8",
            "--addr", str(address), "--duration", str(duration),
            "--baseline", "pymodbus", "--mbload", str(mbload), "--outdir", outdir,
        ]  # fmt: skip
        for fc in functions:
            command += ["--fc", str(fc)]
        for server in servers:
            command += ["--server", server]
        done = subprocess.run(command, cwd=kit, check=False, timeout=3600)
        status = status or done.returncode
        log = Path(outdir) / "runs-tcp.jsonl"
        if log.is_file():
            for line in log.read_text().splitlines():
                run = json.loads(line)
                run["addr"] = address
                runs.append(run)
    print(_kit_summary(runs))
    return status


def _cpu_us(run: dict[str, Any]) -> float | None:
    """The server's CPU per request (µs): its CPU over the run (warm-up included,
    from /proc) divided by every request it answered (warm-up included)."""
    frac, served = (
        run["cpu"]["server_core_frac"],
        run.get("requests", 0) + run.get("warmup_done", 0),
    )
    if not frac or not served:  # the kit could not read the server's CPU (it reads 0)
        return None
    return float(frac) * float(run["wall_s"]) / served * 1e6


def _kit_summary(runs: list[dict[str, Any]]) -> str:
    """Medians by case and server, the ratios against pymodbus and libmodbus."""
    rows = [
        "| words | fc | conns | server | req/s | p99 µs | server CPU µs/request"
        " | × pymodbus | × libmodbus |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    cases = sorted({(r["addr"], r["fc"], r["conns"]) for r in runs})
    for address, fc, conns in cases:
        these = [r for r in runs if (r["addr"], r["fc"], r["conns"]) == (address, fc, conns)]
        servers = sorted({r["server"] for r in these})
        rps = {n: statistics.median(r["rps"] for r in these if r["server"] == n) for n in servers}
        for name in servers:
            mine = [r for r in these if r["server"] == name]
            p99 = statistics.median(r["lat_us"].get("p99", 0) for r in mine)
            cpu = [c for c in map(_cpu_us, mine) if c is not None]
            cpu_text = f"{statistics.median(cpu):.1f}" if cpu else "-"
            ratios = [
                f"{rps[name] / rps[base]:.2f}" if rps.get(base) else "-"
                for base in ("pymodbus", "libmodbus")
            ]
            words = f"{address}..{address + WORDS - 1}"
            rows.append(
                f"| {words} | {fc} | {conns} | {name} | {rps[name]:,.0f} | {p99:,.0f} "
                f"| {cpu_text} | {ratios[0]} | {ratios[1]} |"
            )
    load = runs[-1].get("loadavg") if runs else None
    return "\n".join(rows) + f"\n\nload average at the end: {load}"


def _report(results: dict[str, dict[int, Figures]], duration: float) -> None:
    base = results["pymodbus 3.16 (static datastore)"]
    print(f"Modbus TCP, fc03 read {WORDS} words, {duration:.1f} s per case, loopback")
    print(f"{'server':34} {'conns':>5} {'req/s':>9} {'p50 ms':>8} {'p99 ms':>8} {'x pymodbus':>11}")
    for name, by_conn in results.items():
        for conns, fig in by_conn.items():
            ratio = fig.rps / base[conns].rps
            print(
                f"{name:34} {conns:>5} {fig.rps:>9.0f} {fig.p50_ms:>8.3f} {fig.p99_ms:>8.3f}"
                f" {ratio:>11.2f}"
            )


if __name__ == "__main__":
    main()
