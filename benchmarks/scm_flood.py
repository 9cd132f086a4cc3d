"""A peer floods an SCM channel's pty: memory and the delay of another endpoint (issue 10.4).

One PLC at x1 (paced), two TSX SCM 2111 modules:
  * slot 7 channel 1 (full-duplex, 9600 8N2) on a pty: the flooder writes random bytes to
    it as fast as the pty takes them (``cat /dev/urandom > /dev/pts/N``);
  * slot 6 channel 1 (full-duplex, reception echo + back-space) on TCP loopback: a probe
    sends "a" and BS in turn and times each echo (the other endpoint of the process).
Phase 1 runs the probe alone (quiet), phase 2 with the flood, in the same run.  Printed:
bytes written, characters received and lost, RSS growth (KiB and bytes per byte written),
the probe's median and worst delay in each phase and their ratios.

Usage: .venv/bin/python benchmarks/scm_flood.py [seconds per phase (2)] [MiB to write (3)]
"""

from __future__ import annotations

import os
import socket
import statistics
import sys
import threading
import time

from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.scm.line import RX_BACKLOG

FD_PLAIN = [0x1802, 0x9600, 0, 0, 0, 0, 0, 0, 0]  # SCM 3.2: full-duplex 8N2 9600
FD_ECHO = [0x1802, 0x9600, 0, 0x1001, 0, 0, 0, 0, 0]  # + reception echo and back-space


def rss_kib() -> int:
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def probe(address: tuple[str, int], stop: threading.Event, delays: list[float]) -> None:
    """Send "a" / BS in turn, time until the echo is back ("a", or BS SP BS)."""
    with socket.create_connection(address, timeout=5) as sock:
        for n in range(100_000):  # bounded
            if stop.is_set():
                return
            char, echo = (b"a", 1) if n % 2 == 0 else (b"\x08", 3)
            start = time.perf_counter()
            sock.sendall(char)
            got = 0
            while got < echo:
                got += len(sock.recv(16))
            delays.append(time.perf_counter() - start)
            time.sleep(0.01)


def flood(path: str, stop: threading.Event, budget: int, written: list[int]) -> None:
    chunk = os.urandom(65536)
    fd = os.open(path, os.O_WRONLY | os.O_NOCTTY)
    try:
        while not stop.is_set() and written[0] < budget:
            written[0] += os.write(fd, chunk[: min(len(chunk), budget - written[0])])
    finally:
        os.close(fd)


def phase(
    plc: Plc, seconds: float, address: tuple[str, int], flood_path: str | None, budget: int
) -> tuple[list[float], int]:
    stop = threading.Event()
    delays: list[float] = []
    written = [0]
    threads = [threading.Thread(target=probe, args=(address, stop, delays))]
    if flood_path is not None:
        threads.append(threading.Thread(target=flood, args=(flood_path, stop, budget, written)))
    for thread in threads:
        thread.start()
    plc.advance(seconds)
    stop.set()
    plc.advance(0.1)  # let the probe's last echo out
    for thread in threads:
        thread.join(timeout=5)
    return delays, written[0]


def main() -> None:
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 2.0
    budget = int(float(sys.argv[2] if len(sys.argv) > 2 else 3) * 1024 * 1024)
    plc = Plc(scan_ms=10, speed=1.0)
    flooded = plc.insert("TSX SCM 2111", rack=0, slot=7)
    probed = plc.insert("TSX SCM 2111", rack=0, slot=6)
    plc.advance(1.05)  # the self-tests, unpaced
    assert plc.exchange(m=0x0701, c=0x40, send=FD_PLAIN).v == 0xFE
    assert plc.exchange(m=0x0601, c=0x40, send=FD_ECHO).v == 0xFE
    path = flooded.attach(1, "pty")
    url = probed.attach(1, "tcp://127.0.0.1:0")
    host, port = url.removeprefix("tcp://").rsplit(":", 1)
    address = (host, int(port))
    keep = os.open(path, os.O_RDWR | os.O_NOCTTY)  # hold the pty open between phases

    quiet, _ = phase(plc, seconds, address, None, 0)
    before = rss_kib()
    flooded_delays, written = phase(plc, seconds, address, path, budget)
    growth = rss_kib() - before
    os.close(keep)
    line = flooded.lines[1]
    received = written - line.overruns - line.backlog
    print(f"phase length            {seconds:g} s each, x1, 9600 8N2 (960 characters/s)")
    print(f"bytes written           {written}")
    print(f"characters received     {received}")
    print(f"characters lost         {line.overruns} (overrun)")
    print(f"receiver backlog        {line.backlog} (bound {RX_BACKLOG})")
    print(f"RSS growth              {growth} KiB ({growth * 1024 / max(written, 1):.3f} B/byte)")
    for name, delays in (("quiet", quiet), ("flood", flooded_delays)):
        if delays:
            print(
                f"probe {name:5}             median {statistics.median(delays) * 1e3:6.2f} ms"
                f"  worst {max(delays) * 1e3:6.2f} ms  ({len(delays)} echoes)"
            )
    if quiet and flooded_delays:
        median = statistics.median(flooded_delays) / statistics.median(quiet)
        worst = max(flooded_delays) / max(quiet)
        print(f"ratio flood/quiet       median {median:.2f}  worst {worst:.2f}")
    flooded.detach(1)
    probed.detach(1)


if __name__ == "__main__":
    main()
