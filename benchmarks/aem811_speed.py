"""Simulated seconds per wall second for 1 and 32 TSX AEM 811 (accelerated, 8 channels).

32 modules: a TSX 87 with 8 racks x 4 intelligent modules (slots 0..3).  Every
channel has a sine signal; each module acquires one channel every 100 ms.
Run:  .venv/bin/python benchmarks/aem811_speed.py [simulated_seconds]
"""

from __future__ import annotations

import sys
import time

from fieldtwin.signals import Sine
from fieldtwin.tsx.plc import Plc


def build(count: int) -> Plc:
    plc = Plc(model="TSX 87", scan_ms=10)
    for index in range(count):
        rack, slot = divmod(index, 4)
        mod = plc.insert("TSX AEM 811", rack=rack, slot=slot, code=648)
        for channel in range(8):
            mod.set_signal(channel, Sine(0.0, 8.0, 10_000_000 + 1_000 * channel))
        address = f"{rack}{slot}" if rack else f"{slot}"
        plc.write(f"OW{address},1", 0x0100)  # accelerated, all channels enabled
        plc.write(f"OW{address},0,C", 1)
    plc.advance(10.1)  # initial self-test
    return plc


def measure(count: int, simulated_s: float) -> tuple[float, int]:
    plc = build(count)
    fired = plc.clock.fired
    start = time.perf_counter()
    plc.advance(simulated_s)
    wall = time.perf_counter() - start
    acquisitions = sum(sum(getattr(m, "relay_operations", [])) for m in plc.modules)
    assert acquisitions > 0 and plc.clock.fired > fired
    return simulated_s / wall, acquisitions


def main() -> None:
    simulated = float(sys.argv[1]) if len(sys.argv) > 1 else 60.0
    for count in (1, 32):
        speed, acquisitions = measure(count, simulated)
        print(
            f"{count:2d} x TSX AEM 811, accelerated, 8 channels: "
            f"{speed:8.1f} simulated s per wall s ({acquisitions} acquisitions)"
        )


if __name__ == "__main__":
    main()
