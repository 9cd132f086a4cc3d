"""Simulated seconds per wall second: a PLC with N idle intelligent modules, 10 ms task.

Prints one row per N (1, 8, 32) and the ratio of each to N = 1 (the baseline,
measured in the same run).  An idle module costs only its bus refresh.
"""

from __future__ import annotations

import time

from fieldtwin.tsx import registry
from fieldtwin.tsx.module import IntelligentModule
from fieldtwin.tsx.plc import Plc

SIM_SECONDS = 20.0


class IdleModule(IntelligentModule):
    type_name = "IDLE"
    self_test_us = 10_000


registry.register("IDLE", IdleModule)


def measure(count: int) -> float:
    plc = Plc(model="TSX 87", scan_ms=10)
    for index in range(count):
        plc.insert("IDLE", rack=index // 8, slot=index % 8)
    plc.advance(0.1)
    start = time.perf_counter()
    plc.advance(SIM_SECONDS)
    return SIM_SECONDS / (time.perf_counter() - start)


def main() -> None:
    print(f"PLC TSX 87, 10 ms master task, {SIM_SECONDS:g} simulated seconds per case")
    print(f"{'modules':>8} {'sim s / wall s':>15} {'vs N=1':>8}")
    baseline = None
    for count in (1, 8, 32):
        speed = measure(count)
        baseline = baseline or speed
        print(f"{count:>8} {speed:>15,.0f} {speed / baseline:>8.2f}")


if __name__ == "__main__":
    main()
