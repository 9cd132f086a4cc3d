"""Simulated seconds per second: the default plant, each of its devices alone, idle racks.

What a user sees with ``fieldtwin run --speed max``: the plant built from its file
(the SCM's ptys opened, so the real-time runner paces it, at no speed limit), run
for a stretch of simulated time after the self-tests.  Each case runs twice in the
same process: with the event-driven bus refresh (the default) and with the full
refresh of every slot at every master task (``Plc.event_driven = False``, the old
path kept as the baseline); the ratio is the gain of the refresh alone, the clock,
the program and the module cores being the same in both.

Figures are speed factors over real time: simulated seconds per CPU second of this
process (the figure to compare on a shared machine) and per wall second.

    python benchmarks/sim_speed.py            # the default plant 1 h, devices 10 min
    python benchmarks/sim_speed.py --day      # and the default plant for 24 h
    python benchmarks/sim_speed.py --day --reps 3  # the 24 h three times, and the median
    python benchmarks/sim_speed.py --cli      # and `fieldtwin run` itself, for 1 h
    python benchmarks/sim_speed.py --counts   # and instructions per simulated second

``--counts``: the instructions the default plant executes per simulated second
(benchmarks/counts.py: perf or callgrind on a fixed workload, 60 and 300 simulated
seconds after the warm-up, in fresh processes), which the machine's load does not
move.
"""

from __future__ import annotations

import argparse
import copy
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from fieldtwin.clock import seconds
from fieldtwin.plant import Plant, PlantFile, build_plant, read_plant
from fieldtwin.runtime.binder import SERIAL_LINE, bind
from fieldtwin.tsx import registry
from fieldtwin.tsx.module import IntelligentModule
from fieldtwin.tsx.plc import Plc

WARM_UP_S = 12.0  # the self-tests (10 s) and the program's configuration phase


class IdleModule(IntelligentModule):
    type_name = "IDLE"
    self_test_us = 10_000


registry.register("IDLE", IdleModule)


def default_data() -> dict[str, Any]:
    return copy.deepcopy(dict(read_plant(None).data))


def modules_of(data: Mapping[str, Any], *types: str) -> list[dict[str, Any]]:
    return [m for m in data.get("module", []) if m["type"] in types]


def alone(kind: str) -> dict[str, Any]:
    """The default plant with only ``kind`` kept (as configured there)."""
    data = default_data()
    plc = {"model": data["plc"]["model"], "scan_ms": data["plc"]["scan_ms"]}
    out: dict[str, Any] = {"plant": {"name": kind}}
    if kind == "AEM 811 application":  # the module, its discrete modules and the program
        out["plc"] = {k: v for k, v in data["plc"].items() if k != "outputs"}
        # and the DEM 2412, whose stack the program empties (its words are in the program)
        types = ("TSX AEM 811", "TSX DET 805", "TSX DST 1635", "TSX DEM 2412")
        out["module"] = modules_of(data, *types)
    elif kind.startswith("TES"):
        out["tes"] = [t for t in data["tes"] if t["model"] == kind]
    else:
        out["plc"] = plc
        out["module"] = modules_of(data, kind)
        if kind == "TSX DEM 2412":
            plc["outputs"] = data["plc"]["outputs"]  # to Run, channels 0..3 logged
    return out


def build(data: Mapping[str, Any]) -> Plant:
    plant = build_plant(PlantFile("<benchmark plant>", data, Path(".")), speed=None)
    plant.bindings.append(bind(plant.devices, None, groups=(SERIAL_LINE,), events=plant.events))
    return plant


def advancer(plant: Plant) -> Callable[[float], None]:
    plc = plant.plc
    if plc is not None:
        return plc.advance
    return lambda s: plant.clock.advance(seconds(s))


def timed(run: Callable[[], None]) -> tuple[float, float]:
    """(CPU seconds, wall seconds) of ``run()``."""
    cpu, wall = time.process_time(), time.perf_counter()
    run()
    return time.process_time() - cpu, time.perf_counter() - wall


def measure(make: Callable[[], Plant], sim_s: float, event_driven: bool) -> tuple[float, float]:
    plant = make()
    try:
        if plant.plc is not None:
            plant.plc.event_driven = event_driven
        advance = advancer(plant)
        advance(WARM_UP_S)
        cpu, wall = timed(lambda: advance(sim_s))
        return sim_s / cpu, sim_s / wall
    finally:
        plant.close()


def row(
    name: str, sim_s: float, make: Callable[[], Plant], baseline: bool = True
) -> tuple[float, float]:
    cpu, wall = measure(make, sim_s, True)
    line = f"{name:<34} {sim_s / 3600:>5.2f} h {cpu:>9,.0f}x {wall:>9,.0f}x"
    if baseline:
        cpu0, wall0 = measure(make, sim_s, False)
        line += f" {cpu0:>9,.0f}x {wall0:>9,.0f}x {cpu / cpu0:>7.2f}"
    print(line, flush=True)
    return cpu, wall


def idle_rack(count: int) -> Callable[[], Plant]:
    def make() -> Plant:
        plc = Plc(model="TSX 87", scan_ms=10, speed=None)
        for index in range(count):
            plc.insert("IDLE", rack=index // 8, slot=index % 8)
        return Plant("idle", "idle rack", plc.clock, plc)

    return make


def workload(sim_s: int) -> None:
    """The counted work: the default plant, ``sim_s`` simulated seconds after its warm-up."""
    plant = build(default_data())
    try:
        advance = advancer(plant)
        advance(WARM_UP_S)
        advance(float(sim_s))
    finally:
        plant.close()
    print(f"units {sim_s}")


def cli(sim_s: float) -> None:
    command = [sys.executable, "-m", "fieldtwin", "run", "--speed", "max"]
    command += ["--duration", str(sim_s), "--no-live", "--no-control"]
    command += ["--status-every", str(10 * sim_s)]
    start = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True, timeout=3600)
    wall = time.perf_counter() - start
    name = "fieldtwin run, default plant"
    print(
        f"{name:<34} {sim_s / 3600:>5.2f} h {'':>10} {sim_s / wall:>9,.0f}x"
        f"   ({wall:.1f} s wall, start-up and the TES endpoints included)"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--day", action="store_true", help="also the default plant for 24 h")
    parser.add_argument("--cli", action="store_true", help="also `fieldtwin run` for 1 h")
    parser.add_argument("--hour", type=float, default=3600.0, help="the default plant's stretch")
    parser.add_argument("--device", type=float, default=600.0, help="each device's stretch")
    parser.add_argument("--counts", action="store_true", help="instructions per simulated s")
    parser.add_argument("--reps", type=int, default=1, help="runs of the 24 h (--day): median")
    parser.add_argument("--workload", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.workload is not None:
        workload(args.workload)
        return 0
    print("speed factor over real time (simulated s per CPU s / per wall s); one process")
    head = f"{'case':<34} {'sim':>7} {'cpu':>10} {'wall':>10}"
    print(head + f" {'full cpu':>10} {'full wall':>10} {'gain':>7}")
    print(" " * 53 + "(full refresh of every slot at every task: the baseline)")
    row("default plant (AEM program)", args.hour, lambda: build(default_data()))
    if args.day:
        days = [
            row("default plant (AEM program)", 86400.0, lambda: build(default_data()), False)
            for _ in range(max(1, args.reps))
        ]
        if len(days) > 1:
            cpu = statistics.median(d[0] for d in days)
            wall = statistics.median(d[1] for d in days)
            name = f"  median of {len(days)}"
            print(f"{name:<34} {24:>5.2f} h {cpu:>9,.0f}x {wall:>9,.0f}x", flush=True)
    no_program = default_data()
    for key in ("program", "text_blocks"):
        no_program["plc"].pop(key)
    row("default plant without its program", args.hour, lambda: build(no_program))
    for kind in (
        "AEM 811 application",
        "TSX AEM 811",
        "TSX DEM 2412",
        "TSX SCM 2111",
        "TSX DET 805",
        "TSX DST 1635",
    ):
        data = alone(kind)
        row(f"{kind} alone", args.device, lambda d=data: build(d))  # type: ignore[misc]
    for kind in ("TES 32EST", "TES 8EA"):
        data = alone(kind)
        row(f"{kind} alone (no PLC)", args.device, lambda d=data: build(d), False)  # type: ignore[misc]
    for count in (0, 1, 8, 32):
        row(f"TSX 87, {count} idle modules", args.device, idle_rack(count))
    if args.cli:
        cli(args.hour)
    if args.counts:
        from counts import per_unit

        result = per_unit(__file__, 60, 300, "simulated second")
        print(f"default plant (AEM program): {result}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
