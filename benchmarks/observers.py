"""What watching costs the plant: Modbus TCP throughput with observers, as ratios to none.

Six ``fieldtwin run`` processes (a TES 32EST, slave 1, on a free loopback port; the
control API on a free port; ``--speed 1``) are started once:

* ``plain``   nothing watches;
* ``sub1``    one ``/events`` WebSocket subscriber (every kind; ``batch=1``, as
              fieldtwin.client and the dashboard subscribe);
* ``sub4``    four ``/events`` subscribers (the same);
* ``sub1each`` one subscriber taking one event per message (no ``batch``: websocat);
* ``trace``   ``--trace FILE``;
* ``pcap``    ``--pcap FILE``;
* ``record``  ``--record FILE``.

The shared kit's C load generator (``mbload``: 8 connections, FC03 x 10 words at
word 37, closed loop, one epoll thread) then loads each in turn, the order flipped on
every repetition, so that all of them meet the same machine noise.  Printed per case:
the median requests per second and its ratio to ``plain``; the server's CPU time per
request (utime + stime from /proc of the server and its observers' process, over the
load and the drain after it: what the work costs, which the load on the machine
disturbs less than throughput); and what the observers got: for subscribers, the
``modbus`` events received and those reported dropped against the two frames
(request, reply) of every request sent; for the files, the trace lines, pcap data
packets and recorded ``data`` inputs once the servers stopped.

Subscribers run in a process of their own (``--subscribe``, asyncio + websockets),
so they never share the server's GIL.  Everything started is stopped by its process id.

    .venv/bin/python benchmarks/observers.py [--duration 5] [--reps 3] [--kit ../shared/bench]

The kit's load generator is built by ``bash ../shared/bench/build.sh`` into
``$BENCH_BUILD`` (default /tmp/fieldtwin-bench); never copied here.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import gzip
import json
import os
import re
import signal
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

CASES = ("plain", "sub1", "sub4", "trace", "pcap", "record", "sub1each")
SUBSCRIBERS = {"sub1": 1, "sub4": 4, "sub1each": 1}
CONNS = 8
ADDR = 37
START_TIMEOUT_S = 60.0
SETTLE_S = 0.5  # the subscribers' counts stable this long: their backlog is drained
SETTLE_MAX_S = 30.0
TICK = os.sysconf("SC_CLK_TCK")
PLANT = (
    '[plc]\nmodel = "TSX 87"\nscan_ms = 10\n'
    '[[tes]]\nmodel = "TES 32EST"\nslave = 1\nendpoint = "tcp://127.0.0.1:0"\n'
)


# --- the subscriber process -----------------------------------------------------------


def subscribe_main(url: str, count: int) -> None:
    """``count`` WebSockets on ``url``; a line on stdin asks for the counts (JSON)."""
    import websockets.asyncio.client as ws_client

    received = [0] * count
    modbus = [0] * count
    dropped = [0] * count

    async def one(index: int) -> None:
        async with ws_client.connect(url, max_size=2**24, ping_interval=None) as socket:
            ready.release()
            async for message in socket:
                # counted, not decoded: this process shares the 2 cores with the plant
                # and the load generator, and must not be what limits the plant (four
                # subscribers decoding every event cost more CPU than the plant's
                # process itself); a message that tells of dropped events is decoded
                text = message if isinstance(message, str) else message.decode()
                received[index] += text.count('"t_s":') + text.count('"kind":"dropped"')
                modbus[index] += text.count('"kind":"modbus"')
                if '"kind":"dropped"' in text:
                    items = json.loads(text)
                    for item in items if isinstance(items, list) else [items]:
                        if item.get("kind") == "dropped":
                            dropped[index] += int(item["count"])

    ready = threading.Semaphore(0)

    async def main() -> None:
        tasks = [asyncio.create_task(one(i)) for i in range(count)]
        loop = asyncio.get_running_loop()
        while True:
            line = await loop.run_in_executor(None, sys.stdin.readline)
            if not line:
                break
            state = {"received": received, "modbus": modbus, "dropped": dropped}
            print(json.dumps(state), flush=True)
        for task in tasks:
            task.cancel()

    def announce() -> None:
        for _ in range(count):
            ready.acquire()
        print("ready", flush=True)

    threading.Thread(target=announce, daemon=True).start()
    asyncio.run(main())


# --- servers --------------------------------------------------------------------------


@dataclass
class Server:
    case: str
    proc: subprocess.Popen[str]
    port: int
    control: str
    files: dict[str, Path]
    subscriber: subprocess.Popen[str] | None = None
    rps: list[float] = field(default_factory=list)
    cpu_us: list[float] = field(default_factory=list)
    sent: int = 0  # requests answered (warm-up included)
    events: list[tuple[int, int]] = field(default_factory=list)  # (modbus, dropped) per run
    told: list[str] = field(default_factory=list)  # what it said on closing that matters

    def ticks(self) -> int:
        """CPU ticks of the server and of its children (the observers' process)."""
        return sum(_ticks(pid) for pid in (self.proc.pid, *_children(self.proc.pid)))

    def counts(self) -> dict[str, list[int]] | None:
        sub = self.subscriber
        if sub is None:
            return None
        assert sub.stdin is not None and sub.stdout is not None
        sub.stdin.write("?\n")
        sub.stdin.flush()
        answer: dict[str, list[int]] = json.loads(sub.stdout.readline())
        return answer


def _ticks(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/stat") as f:
            rest = f.read().rsplit(")", 1)[1].split()
        return int(rest[11]) + int(rest[12])
    except (OSError, IndexError, ValueError):
        return 0


def _children(pid: int) -> list[int]:
    out: list[int] = []
    try:
        for task in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{task}/children") as f:
                out.extend(int(child) for child in f.read().split())
    except (OSError, ValueError):
        pass
    return out


def _read_line(stream: IO[str], pattern: str, deadline: float, seen: list[str]) -> str:
    while time.monotonic() < deadline:
        line = stream.readline()
        if not line:
            break
        seen.append(line)
        match = re.search(pattern, line)
        if match:
            return match.group(1)
    raise RuntimeError(f"no line matching {pattern!r}; got: {''.join(seen)[-2000:]}")


def start(case: str, tmp: Path) -> Server:
    plant = tmp / "plant.toml"
    plant.write_text(PLANT, "utf-8")
    files: dict[str, Path] = {}
    extra: list[str] = []
    if case in ("trace", "pcap", "record"):
        suffix = {"trace": "jsonl", "pcap": "pcap", "record": "ftrec"}[case]
        files[case] = tmp / f"{case}.{suffix}"
        extra = [f"--{case}", str(files[case])]
    command = [sys.executable, "-m", "fieldtwin", "run", str(plant), "--no-live"]
    command += ["--speed", "1", "--control-port", "0", *extra]
    proc = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1
    )
    assert proc.stdout is not None
    deadline, seen = time.monotonic() + START_TIMEOUT_S, []
    try:
        port = int(_read_line(proc.stdout, r"modbus-tcp tcp://127\.0\.0\.1:(\d+)", deadline, seen))
        control = _read_line(proc.stdout, r"^control: (http://\S+)", deadline, seen)
    except BaseException:
        _stop(proc)
        raise
    server = Server(case, proc, port, control, files)
    threading.Thread(target=_drain_output, args=(proc.stdout, server), daemon=True).start()
    if case in SUBSCRIBERS:
        url = control.replace("http://", "ws://") + "/events"
        url += "" if case.endswith("each") else "?batch=1"
        sub = subprocess.Popen(
            [sys.executable, __file__, "--subscribe", url, str(SUBSCRIBERS[case])],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            bufsize=1,
        )
        server.subscriber = sub
        assert sub.stdout is not None
        _read_line(sub.stdout, r"^(ready)", time.monotonic() + START_TIMEOUT_S, [])
    return server


def _drain_output(stream: IO[str], server: Server) -> None:
    for line in stream:
        if "waited" in line or "observer failed" in line:  # a recording's writer; a bug
            server.told.append(line.strip())


def _stop(proc: subprocess.Popen[str], sig: int = signal.SIGINT) -> None:
    if proc.poll() is None:
        proc.send_signal(sig)
        try:
            proc.wait(60)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


# --- one run --------------------------------------------------------------------------


def load(mbload: Path, server: Server, duration: float) -> None:
    before_counts = server.counts()
    before = server.ticks()
    command = [str(mbload), "--port", str(server.port), "--conns", str(CONNS)]
    command += ["--duration", str(duration), "--fc", "3", "--addr", str(ADDR), "--json"]
    done = subprocess.run(
        command, capture_output=True, text=True, check=False, timeout=duration + 120
    )
    result = json.loads(done.stdout)
    errors = sum(result["errors"].values())
    if errors:
        print(f"  {server.case}: {errors} failed requests {result['errors']}", file=sys.stderr)
    answered = int(result["requests"]) + int(result.get("warmup_done", 0))
    server.sent += answered
    after_counts = _settle(server)
    spent = (server.ticks() - before) / TICK
    server.rps.append(float(result["rps"]))
    server.cpu_us.append(spent / max(answered, 1) * 1e6)
    if before_counts is not None and after_counts is not None:
        got = sum(after_counts["modbus"]) - sum(before_counts["modbus"])
        lost = sum(after_counts["dropped"]) - sum(before_counts["dropped"])
        subs = len(after_counts["modbus"])
        server.events.append((got, lost))
        expected = 2 * answered * subs
        print(
            f"  {server.case}: {result['rps']:.0f} req/s; events {got} + dropped {lost}"
            f" of {expected} frames x subscribers",
            file=sys.stderr,
        )
    else:
        print(f"  {server.case}: {result['rps']:.0f} req/s", file=sys.stderr)


def _settle(server: Server) -> dict[str, list[int]] | None:
    """Wait (bounded) until the subscribers' counts stop moving: their backlog is in."""
    counts = server.counts()
    if counts is None:
        time.sleep(SETTLE_S)
        return None
    deadline = time.monotonic() + SETTLE_MAX_S
    while time.monotonic() < deadline:
        time.sleep(SETTLE_S)
        again = server.counts()
        if again == counts:
            break
        counts = again
    return counts


# --- what the files hold --------------------------------------------------------------


def file_counts(server: Server) -> str:
    if "trace" in server.files:
        path = server.files["trace"]
        lines = sum(1 for line in path.open("rb") if b'"kind":"modbus"' in line)
        return f"trace: {lines} modbus lines of {2 * server.sent} frames"
    if "pcap" in server.files:
        packets = _pcap_data_packets(server.files["pcap"])
        return f"pcap: {packets} data packets of {2 * server.sent} frames"
    if "record" in server.files:
        with gzip.open(server.files["record"], "rb") as f:
            data = sum(1 for line in f if line.startswith(b'["data"'))
        waited = "; ".join(server.told) or "the plant never waited for the writer"
        return f"record: {data} data inputs of {server.sent} requests; {waited}"
    return ""


def _pcap_data_packets(path: Path) -> int:
    """Packets with a TCP payload (the handshakes carry none)."""
    raw = path.read_bytes()
    offset, packets = 24, 0
    while offset + 16 <= len(raw):
        length = struct.unpack_from("<I", raw, offset + 8)[0]
        frame = raw[offset + 16 : offset + 16 + length]
        offset += 16 + length
        if len(frame) > 14 + 20:
            ihl = (frame[14] & 0x0F) * 4
            tcp = 14 + ihl
            header = (frame[tcp + 12] >> 4) * 4 if len(frame) > tcp + 12 else 0
            packets += len(frame) > tcp + header
    return packets


# --- main -----------------------------------------------------------------------------


def report(servers: dict[str, Server], duration: float, reps: int) -> None:
    plain = statistics.median(servers["plain"].rps)
    plain_cpu = statistics.median(servers["plain"].cpu_us)
    print(
        f"\nfieldtwin run, TES 32EST, mbload {CONNS} connections FC03 x10, "
        f"{duration:g} s x {reps} alternated runs, {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    print(f"{'case':<9} {'req/s':>8} {'ratio':>6} {'cpu us/req':>10} {'cpu ratio':>9}  observers")
    for case, server in servers.items():
        rps, cpu = statistics.median(server.rps), statistics.median(server.cpu_us)
        seen = ""
        if server.events:
            got = sum(g for g, _ in server.events)
            lost = sum(d for _, d in server.events)
            seen = f"events {got} + dropped {lost}"
        seen = seen or file_counts(server)
        print(
            f"{case:<9} {rps:8.0f} {rps / plain:5.2f}x {cpu:10.1f} {cpu / plain_cpu:8.2f}x  {seen}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=5.0, help="measured seconds per run")
    parser.add_argument("--reps", type=int, default=3, help="alternated repetitions")
    parser.add_argument("--cases", default=",".join(CASES), help="comma list of " + ",".join(CASES))
    parser.add_argument("--subscribe", nargs=2, metavar=("URL", "N"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.subscribe:
        subscribe_main(args.subscribe[0], int(args.subscribe[1]))
        return
    mbload = Path(os.environ.get("BENCH_BUILD", "/tmp/fieldtwin-bench")) / "mbload"
    if not mbload.is_file():
        raise SystemExit(f"no {mbload}: build it with bash ../shared/bench/build.sh")
    cases = [c for c in args.cases.split(",") if c]
    unknown = set(cases) - set(CASES)
    if unknown or "plain" not in cases:
        raise SystemExit(f"--cases: plain and any of {', '.join(CASES)}")
    servers: dict[str, Server] = {}
    with tempfile.TemporaryDirectory(prefix="observers_") as tmp:
        try:
            for case in cases:
                (Path(tmp) / case).mkdir()
                servers[case] = start(case, Path(tmp) / case)
            for rep in range(args.reps):
                order = cases if rep % 2 == 0 else cases[::-1]
                print(f"run {rep + 1}/{args.reps}: {' '.join(order)}", file=sys.stderr)
                for case in order:
                    load(mbload, servers[case], args.duration)
        finally:
            for server in servers.values():
                if server.subscriber is not None:
                    with contextlib.suppress(OSError):
                        assert server.subscriber.stdin is not None
                        server.subscriber.stdin.close()
                    _stop(server.subscriber, signal.SIGTERM)
                _stop(server.proc)
        if all(server.rps for server in servers.values()):
            report(servers, args.duration, args.reps)


if __name__ == "__main__":
    main()
