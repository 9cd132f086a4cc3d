"""Modbus RTU answer time on a pty against the TES 7.2.7 formula (issue 15 item 2).

A TES 32EST (slave 1) is served on a pty at each baud rate (8E1) by a server in
its own process (``--speed 1``); this process is the master: it writes each
request at once (a pty carries no baud rate) and times until the reply's last
byte.  With wire timing on (the default) the reply leaves when a real line would
deliver its last character, so the answer time should be

    A = Nb x 1000 / Vt x (Nq + 3.5 + Nr) + tr + answer delay      (tr = 1.5 ms)

which is the §7.2.7 exchange time T = Nb x 1000 / Vt x (Nq + Sq + Nr + Sr) + tq + tr
without the silence after the reply (Sr) and the master's own delay tq, both on
the master's side of the exchange.  Each row prints the median answer time, A,
the difference in character times (goal: within one), T, and the same server
with wire timing off (the baseline measured in the same run).

    .venv/bin/python benchmarks/rtu_timing.py [--requests 60] [--bauds 9600,19200,38400]

Figures are wall-clock on a shared machine: the median of many exchanges is
printed; scheduling noise shows in p90.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import select
import statistics
import termios
import time
import tty
from multiprocessing.queues import Queue

from fieldtwin.clock import SimClock
from fieldtwin.modbus.crc import with_crc
from fieldtwin.modbus.model import Link, ReadWords, Request, WriteWord, WriteWords
from fieldtwin.modbus.pdu import encode_request
from fieldtwin.modbus.timing import exchange_time_us, reply_bytes, reply_latency_us
from fieldtwin.runtime.modbus_server import serve_rtu
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.base import line_settings
from fieldtwin.transports.pty import open_pty

SLAVE = 1
ADDRESS = 0x025  # the 32-bit area of a TES 32EST: read/write (counters)
TIMEOUT_S = 3.0
CASES: tuple[tuple[str, Request], ...] = (
    ("fc03 x10", ReadWords(3, ADDRESS, 10)),
    ("fc06", WriteWord(ADDRESS + 1, 7)),
    ("fc16 x10", WriteWords(ADDRESS, tuple(range(10)))),
)


def _serve(baud: int, wire: bool, paths: Queue[str]) -> None:
    from fieldtwin.tes import Tes

    clock = SimClock()
    tes = Tes("TES 32EST", SLAVE, clock=clock)
    tes.write_eeprom({"rs485.baud": baud})
    tes.power_cycle()
    settings = line_settings(baud=baud, parity="E")
    runner = Runner(clock, speed=1.0)
    transport = open_pty(settings)
    serve_rtu(runner, transport, [tes], Link.RS485, settings, wire_timing=wire)
    assert transport.peer_path is not None
    paths.put(transport.peer_path)
    runner.run_forever()


def _exchange(fd: int, frame: bytes, expect: int) -> float:
    start = time.perf_counter()
    os.write(fd, frame)
    got = b""
    while len(got) < expect:
        left = TIMEOUT_S - (time.perf_counter() - start)
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            raise SystemExit(f"no reply within {TIMEOUT_S} s (got {got.hex()})")
        got += os.read(fd, 512)
    return time.perf_counter() - start


def _measure(baud: int, wire: bool, requests: int) -> dict[str, list[float]]:
    paths: Queue[str] = mp.Queue()
    server = mp.Process(target=_serve, args=(baud, wire, paths), daemon=True)
    server.start()
    try:
        path = paths.get(timeout=20)
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        try:
            tty.setraw(fd)
            termios.tcflush(fd, termios.TCIOFLUSH)
            out: dict[str, list[float]] = {}
            for name, request in CASES:
                frame = with_crc(bytes((SLAVE,)) + encode_request(request))
                expect = reply_bytes(request)
                _exchange(fd, frame, expect)  # warm-up
                samples = []
                for _ in range(requests):
                    samples.append(_exchange(fd, frame, expect))
                    time.sleep(0.005)  # a silence between exchanges, as a master keeps
                out[name] = samples
            return out
        finally:
            os.close(fd)
    finally:
        server.terminate()
        server.join(5)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--requests", type=int, default=60, help="exchanges per case")
    parser.add_argument("--bauds", default="9600,19200,38400", help="comma list")
    args = parser.parse_args()
    mp.set_start_method("spawn", force=True)
    print("Modbus RTU on a pty, 8E1, TES 32EST, answer time = request written .. reply's last byte")
    head = f"{'baud':>6} {'case':9} {'median ms':>9} {'p90 ms':>7} {'A ms':>7}"
    print(f"{head} {'diff chars':>10} {'T ms':>7} {'off ms':>7}")
    worst = 0.0
    for baud in (int(b) for b in args.bauds.split(",")):
        fmt = line_settings(baud=baud, parity="E")
        wired = _measure(baud, True, args.requests)
        plain = _measure(baud, False, args.requests)
        char_ms = float(fmt.char_time) / 1000
        for name, request in CASES:
            nq = len(encode_request(request)) + 3
            nr = reply_bytes(request)
            a_ms = reply_latency_us(fmt, nq, nr) / 1000
            t_ms = exchange_time_us(fmt.bits, baud, nq, nr) / 1000
            samples = sorted(wired[name])
            median = statistics.median(samples) * 1000
            p90 = samples[int(len(samples) * 0.9)] * 1000
            diff = (median - a_ms) / char_ms
            worst = max(worst, abs(diff))
            off = statistics.median(plain[name]) * 1000
            print(
                f"{baud:>6} {name:9} {median:>9.3f} {p90:>7.3f} {a_ms:>7.3f}"
                f" {diff:>+10.2f} {t_ms:>7.3f} {off:>7.3f}"
            )
    print(f"largest |median - A|: {worst:.2f} character times (goal: <= 1)")


if __name__ == "__main__":
    main()
