"""A fast Modbus TCP client while others connect, idle, close, churn, or never read.

Issue 10 items 2 and 3.  One server process (our glue, a static table device, paced at
x1), one fast client process (closed loop: send "read 10 holding registers", wait for
the reply, repeat) and one crowd process.  Each case measures the fast client for
``--duration`` seconds while the crowd:

* quiet     does nothing (the reference of every ratio, measured in the same run)
* opening   opens ``--connections`` connections (2,000) as fast as it can
* idle      holds them open, silent
* closing   closes them all
* churn     connects and closes one connection ``--churn`` times a second
* no-reader sends requests as fast as the kernel takes them and never reads an answer
* quiet again, last: the reference is the mean of the two quiet cases

It prints requests/s, p50 and p99 per case, the ratios to the quiet case, the server's
CPU time per fast-client request (a figure that other processes on a shared machine
do not disturb) and the server's resident memory (the no-reader case must not grow it).
Targets (issue 10): p99 below 2 ms, throughput within 20 % of quiet.  No assertion:
figures only.
Loopback only; every wait is bounded; the crowd raises its own descriptor limit
where the hard limit allows, and says so when it has to open fewer.

    .venv/bin/python benchmarks/connections.py [--duration 2] [--connections 2000]
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import resource
import socket
import statistics
import sys
import time
from dataclasses import dataclass
from multiprocessing.connection import Connection

from fieldtwin.clock import SimClock
from fieldtwin.modbus.mbap import encode_mbap
from fieldtwin.modbus.model import Counter, Link, ReadWords, Request, Result
from fieldtwin.modbus.pdu import encode_request
from fieldtwin.runtime.modbus_server import serve_tcp
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.tcp import listen

WORDS = 10
UNIT = 1
REPLY_SIZE = 9 + 2 * WORDS
TIMEOUT_S = 30.0  # bound on every answer between processes
REQUEST = encode_mbap(1, UNIT, encode_request(ReadWords(3, 0, WORDS)))


def _raise_fd_limit(wanted: int) -> int:
    """Raise the soft descriptor limit towards ``wanted``; return what we have."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    target = wanted if hard == resource.RLIM_INFINITY else min(wanted, hard)
    if target > soft:
        resource.setrlimit(resource.RLIMIT_NOFILE, (target, hard))
    return resource.getrlimit(resource.RLIMIT_NOFILE)[0]


class Table:
    """256 static holding words (the device behind the server)."""

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


def _server(connections: int, pipe: Connection) -> None:
    _raise_fd_limit(connections + 256)
    clock = SimClock()
    runner = Runner(clock, speed=1.0)
    listener = listen("127.0.0.1", 0, max_connections=connections + 16)
    serve_tcp(runner, listener, [Table(UNIT)])
    pipe.send(listener.address[1])
    runner.run_forever()


def _cpu_s(pid: int) -> float:
    """User + system CPU seconds of ``pid`` so far (insensitive to other processes' load)."""
    with open(f"/proc/{pid}/stat") as stat:
        fields = stat.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _rss_kib(pid: int) -> int:
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


# --- the fast client ----------------------------------------------------------------


def _fast_client(port: int, pipe: Connection) -> None:
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    while (duration := pipe.recv()) is not None:
        latencies: list[float] = []
        end = time.perf_counter() + duration
        while (t0 := time.perf_counter()) < end:
            sock.sendall(REQUEST)
            got = 0
            while got < REPLY_SIZE:
                chunk = sock.recv(4096)
                if not chunk:
                    raise SystemExit("the server closed the fast client's connection")
                got += len(chunk)
            latencies.append(time.perf_counter() - t0)
        pipe.send(latencies)
    sock.close()


# --- the crowd ----------------------------------------------------------------------


def _crowd(port: int, connections: int, churn: float, pipe: Connection) -> None:
    have = _raise_fd_limit(connections + 64)
    count = min(connections, max(0, have - 64))
    pipe.send(count)
    idle: list[socket.socket] = []
    while (command := pipe.recv()) is not None:
        if command == "open":
            for _ in range(count):
                idle.append(socket.create_connection(("127.0.0.1", port), timeout=5))
        elif command == "close":
            for sock in idle:
                sock.close()
            idle.clear()
        elif isinstance(command, tuple) and command[0] == "churn":
            _churn(port, churn, command[1])
        elif isinstance(command, tuple) and command[0] == "no-reader":
            _no_reader(port, command[1])
        pipe.send("done")


def _churn(port: int, rate: float, duration: float) -> None:
    start = time.perf_counter()
    n = 0
    while (now := time.perf_counter()) < start + duration:
        due = start + n / rate
        if now < due:
            time.sleep(due - now)
        socket.create_connection(("127.0.0.1", port), timeout=5).close()
        n += 1


def _no_reader(port: int, duration: float) -> None:
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    sock.setblocking(False)
    burst = REQUEST * 256
    end = time.perf_counter() + duration
    while time.perf_counter() < end:
        try:
            sock.send(burst)
        except BlockingIOError:
            time.sleep(0.001)  # the server stopped reading us: TCP holds us back
    sock.close()


# --- the run ------------------------------------------------------------------------


@dataclass(frozen=True)
class Figures:
    rps: float
    p50_ms: float
    p99_ms: float
    rss_kib: int
    cpu_us: float  # server CPU per fast-client request


def _figures(latencies: list[float], duration: float, rss: int, cpu_s: float) -> Figures:
    if not latencies:
        raise SystemExit("no request completed")
    ordered = sorted(latencies)
    p99 = ordered[min(len(ordered) - 1, int(len(ordered) * 0.99))]
    median = statistics.median(ordered) * 1e3
    cpu_us = cpu_s * 1e6 / len(ordered)
    return Figures(len(ordered) / duration, median, p99 * 1e3, rss, cpu_us)


def _measure(fast: Connection, crowd: Connection, command: object, duration: float) -> list[float]:
    """Measure the fast client while the crowd does ``command`` (None: nothing)."""
    if command is not None:
        crowd.send(command)
    fast.send(duration)
    if not fast.poll(duration + TIMEOUT_S):
        raise SystemExit("the fast client did not answer")
    latencies: list[float] = fast.recv()
    if command is not None:
        if not crowd.poll(TIMEOUT_S + duration):
            raise SystemExit(f"the crowd did not finish {command!r}")
        crowd.recv()
    return latencies


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=2.0, help="seconds per case")
    parser.add_argument("--connections", type=int, default=2000, help="idle connections")
    parser.add_argument("--churn", type=float, default=200.0, help="connects per second")
    args = parser.parse_args()
    duration = args.duration
    mp.set_start_method("spawn", force=True)
    server_end, ours = mp.Pipe()
    server = mp.Process(target=_server, args=(args.connections, server_end), daemon=True)
    server.start()
    procs = [server]
    try:
        if not ours.poll(TIMEOUT_S):
            raise SystemExit("the server did not start")
        port = ours.recv()
        fast_end, fast = mp.Pipe()
        crowd_end, crowd = mp.Pipe()
        procs.append(mp.Process(target=_fast_client, args=(port, fast_end), daemon=True))
        procs.append(
            mp.Process(
                target=_crowd, args=(port, args.connections, args.churn, crowd_end), daemon=True
            )
        )
        for proc in procs[1:]:
            proc.start()
        count = crowd.recv() if crowd.poll(TIMEOUT_S) else 0
        if count < args.connections:
            print(f"descriptor limit: the crowd opens {count} connections, not {args.connections}")
        assert server.pid is not None
        results: dict[str, Figures] = {}
        _measure(fast, crowd, None, 0.5)  # warm up
        cases: list[tuple[str, object]] = [
            ("quiet", None),
            (f"opening {count}", "open"),
            (f"{count} idle", None),
            (f"closing {count}", "close"),
            (f"churn {args.churn:g}/s", ("churn", duration)),
            ("no-reader", ("no-reader", duration)),
            ("after no-reader", None),
            ("quiet again", None),
        ]
        for name, command in cases:
            cpu0 = _cpu_s(server.pid)
            latencies = _measure(fast, crowd, command, duration)
            cpu = _cpu_s(server.pid) - cpu0
            results[name] = _figures(latencies, duration, _rss_kib(server.pid), cpu)
            print(f"  done: {name}", file=sys.stderr, flush=True)
        fast.send(None)
        crowd.send(None)
        _report(results, duration)
    finally:
        for proc in procs:
            proc.terminate()
            proc.join(5)


def _report(results: dict[str, Figures], duration: float) -> None:
    # the reference: both quiet cases (first and last), so a drift of the machine's
    # load during the run shows as their difference, not as a ratio
    first, last = results["quiet"], results["quiet again"]
    quiet = Figures(
        (first.rps + last.rps) / 2,
        0.0,
        (first.p99_ms + last.p99_ms) / 2,
        first.rss_kib,
        (first.cpu_us + last.cpu_us) / 2,
    )
    print(f"fast client, Modbus TCP fc03 {WORDS} words, {duration:g} s per case, loopback, x1")
    print(
        f"{'case':18} {'req/s':>8} {'p50 ms':>7} {'p99 ms':>7} {'rps/quiet':>9}"
        f" {'p99/quiet':>9} {'cpu us/req':>10} {'cpu/quiet':>9} {'server RSS':>11}"
    )
    for name, fig in results.items():
        print(
            f"{name:18} {fig.rps:>8.0f} {fig.p50_ms:>7.3f} {fig.p99_ms:>7.3f}"
            f" {fig.rps / quiet.rps:>9.2f} {fig.p99_ms / quiet.p99_ms:>9.2f}"
            f" {fig.cpu_us:>10.1f} {fig.cpu_us / quiet.cpu_us:>9.2f}"
            f" {fig.rss_kib / 1024:>8.1f} MiB"
        )
    print("ratios against the mean of the two quiet cases; cpu us/req is the server's CPU")
    print("time per fast-client request (crowd work included), unaffected by other load")
    print("targets: p99 below 2 ms, req/s at least 0.80 of quiet")


if __name__ == "__main__":
    main()
