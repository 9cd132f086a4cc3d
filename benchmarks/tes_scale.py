"""How the cost of a plant grows with its TES (issue 15): start-up, memory, speed, RTU frames.

Each case runs in a fresh process (so RSS is its own), built the way ``fieldtwin
run`` builds a plant (plant file -> build_plant -> bind):

* N = 1, 10, 100, 1000 TES 32EST on 5 Modbus TCP endpoints: start-up (build and
  open the endpoints, imports excluded), peak RSS, and simulated seconds per wall
  second at ``--speed max`` with one 1 Hz pulse train on input 0 of each TES; the
  same with every TES read by a master once a simulated second (its rise counter,
  its filtered inputs: the inputs followed at read time are caught up then), and,
  as the baseline measured in the same run, the same polled plant with an event
  per edge (``DigitalInputs.lazy = False``, the code before read-time inputs);
* 247 TES on one RTU line (a pty): start-up, RSS, and, with a master on the pty,
  one FC03 to every slave with its answer checked, the server's cost per frame
  against the same line with 1 TES (the baseline, same run): no O(N) per frame.

    .venv/bin/python benchmarks/tes_scale.py [--sim 10]

Wall-clock figures on a shared machine: compare the ratios of one run.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import resource
import select
import subprocess
import sys
import tempfile
import termios
import time
import tty
from pathlib import Path

PULSE = '{ 0 = { kind = "pulse", period_s = 1.0, duty = 0.5 } }'


def _plant(count: int, rtu: bool, pulse: bool) -> Path:
    lines = ["[plant]", 'name = "scale"', ""]
    base = 20000 + os.getpid() % 20000
    for i in range(count):
        endpoint = "pty" if rtu else f"tcp://127.0.0.1:{base + i % 5}"
        slave = i + 1 if rtu else i // 5 + 1
        lines += ["[[tes]]", 'model = "TES 32EST"', f"slave = {slave}", f'endpoint = "{endpoint}"']
        if pulse:
            lines.append(f"inputs = {PULSE}")
        lines.append("")
    path = Path(tempfile.mkdtemp(prefix="tes_scale_"), "plant.toml")
    path.write_text("\n".join(lines))
    return path


def _poll(runner: object, devices: list[object]) -> None:
    """A master reads every TES once a simulated second (FC03: rise counter, inputs)."""
    from fieldtwin.modbus.model import Link, ReadWords
    from fieldtwin.runtime.runner import Runner

    assert isinstance(runner, Runner)
    clock = runner.clock
    teses = [d.tes for d in devices if hasattr(d, "tes")]  # type: ignore[attr-defined]
    counter, inputs = ReadWords(3, 0x025, 2), ReadWords(3, 0x003, 2)

    def poll(now: int) -> None:
        for tes in teses:
            tes.execute(counter, Link.RS485, now, False)
            tes.execute(inputs, Link.RS485, now, False)
        clock.schedule(now + 1_000_000, poll)

    clock.schedule(clock.now + 1_000_000, poll)


def _child(count: int, rtu: bool, sim_s: float, mode: str) -> dict[str, float]:
    from fieldtwin.clock import SimClock
    from fieldtwin.plant import build_plant, read_plant
    from fieldtwin.runtime.binder import bind
    from fieldtwin.runtime.runner import Runner
    from fieldtwin.tes.digital import DigitalInputs

    if mode == "eager":
        DigitalInputs.lazy = False
    path = _plant(count, rtu, pulse=not rtu)
    start = time.perf_counter()
    clock = SimClock()
    runner = Runner(clock, None)
    plant = build_plant(read_plant(path), runner=runner, speed=None)
    binding = bind(plant.devices, runner, events=plant.events)
    out = {"startup_s": time.perf_counter() - start}
    gc.collect()  # as `fieldtwin run` does once the plant is built
    gc.freeze()
    try:
        if rtu:
            out["frame_us"] = _frames(runner, binding.lines, count)
        else:
            if mode != "quiet":
                _poll(runner, plant.devices)
            start = time.perf_counter()
            runner.advance(round(sim_s * 1_000_000))
            out["speed"] = sim_s / (time.perf_counter() - start)
    finally:
        binding.close()
    out["rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return out


def _frames(runner: object, lines: list[str], count: int) -> float:
    """One FC03 to every slave from a master on the pty; the server's time per frame."""
    from fieldtwin.modbus.crc import with_crc
    from fieldtwin.modbus.model import ReadWords
    from fieldtwin.modbus.pdu import encode_request
    from fieldtwin.runtime.runner import Runner

    assert isinstance(runner, Runner)
    path = lines[0].split()[3]
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    tty.setraw(fd)
    termios.tcflush(fd, termios.TCIOFLUSH)
    busy = 0.0
    try:
        for rounds in range(3):
            for slave in range(1, count + 1):
                os.write(fd, with_crc(bytes((slave,)) + encode_request(ReadWords(3, 0x000, 1))))
                got = b""
                t0 = time.process_time()
                while len(got) < 7:
                    if not runner.run_until(lambda: bool(select.select([fd], [], [], 0)[0]), 10**6):
                        raise SystemExit(f"slave {slave}: no answer")
                    got += os.read(fd, 64)
                if rounds:
                    busy += time.process_time() - t0
                expect = with_crc(bytes((slave, 3, 2, 0, 1)))  # status word: power on (§6.2.1)
                if got != expect:
                    raise SystemExit(f"slave {slave}: answered {got.hex()}, not {expect.hex()}")
    finally:
        os.close(fd)
    return busy / (2 * count) * 1e6


def _run(count: int, rtu: bool, sim_s: float, mode: str = "quiet") -> dict[str, float]:
    args = [sys.executable, __file__, "--child", str(count), "--sim", str(sim_s), "--mode", mode]
    if rtu:
        args.append("--rtu")
    done = subprocess.run(args, capture_output=True, text=True, timeout=600, check=False)
    if done.returncode:
        raise SystemExit(done.stderr)
    result: dict[str, float] = json.loads(done.stdout.splitlines()[-1])
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sim", type=float, default=10.0, help="simulated seconds per speed case")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--rtu", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--mode", default="quiet", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child is not None:
        print(json.dumps(_child(args.child, args.rtu, args.sim, args.mode)))
        return
    print("TES 32EST on 5 Modbus TCP endpoints, one 1 Hz pulsing input each, --speed max")
    print("  simulated s per wall s: unread; read by a master every simulated second;")
    print("  the same polled, an event per edge (baseline, same run)")
    head = f"{'TES':>5} {'start-up s':>10} {'RSS MB':>7} {'unread':>9} {'vs N=1':>7}"
    print(f"{head} {'polled':>9} {'baseline':>9} {'ratio':>6}")
    base = None
    for count in (1, 10, 100, 1000):
        r = _run(count, False, args.sim)
        polled = _run(count, False, args.sim, "polled")["speed"]
        eager = _run(count, False, args.sim, "eager")["speed"]
        base = base or r["speed"]
        print(
            f"{count:>5} {r['startup_s']:>10.3f} {r['rss_mb']:>7.0f} {r['speed']:>9,.0f}"
            f" {r['speed'] / base:>7.3f} {polled:>9,.0f} {eager:>9,.0f} {polled / eager:>6.1f}"
        )
    print("TES 32EST on one RTU line (pty), every slave asked FC03 and its answer checked")
    print(f"{'TES':>5} {'start-up s':>10} {'RSS MB':>7} {'us/frame':>9} {'vs N=1':>7}")
    one = _run(1, True, args.sim)
    many = _run(247, True, args.sim)
    for count, r in ((1, one), (247, many)):
        print(
            f"{count:>5} {r['startup_s']:>10.3f} {r['rss_mb']:>7.0f} {r['frame_us']:>9.0f}"
            f" {r['frame_us'] / one['frame_us']:>7.2f}"
        )


if __name__ == "__main__":
    main()
