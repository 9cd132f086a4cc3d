"""Simulated seconds per wall second for a TES 32EST and a TES 8EA with live signals.

.venv/bin/python benchmarks/tes_sim.py [simulated_seconds]
"""

from __future__ import annotations

import sys
import time

from fieldtwin.signals import PulseTrain, Sine
from fieldtwin.tes import Tes


def _measure(tes: Tes, simulated_s: float) -> tuple[float, int]:
    start, fired = time.perf_counter(), tes.clock.fired
    tes.advance(simulated_s)
    return simulated_s / (time.perf_counter() - start), tes.clock.fired - fired


def main(argv: list[str]) -> int:
    simulated = float(argv[0]) if argv else 60.0
    digital = Tes("TES 32EST")
    for i in range(16):  # every input pulsing, 2..17 Hz
        digital.set_signal(i, PulseTrain(period_us=1_000_000 // (i + 2), duty=0.5))
    write_blink = 0x00C
    digital.write(write_blink, 0xFFFF)  # every output blinking (computed at read time)
    analog = Tes("TES 8EA")
    for k in range(8):
        analog.set_signal(k, Sine(5.0, 4.0, 1_000_000 * (k + 1)))
    cases = (("TES 32EST, 16 pulsing inputs", digital), ("TES 8EA, 8 sine inputs", analog))
    for name, tes in cases:
        rate, events = _measure(tes, simulated)
        print(f"{name}: {rate:,.0f} simulated s per wall s ({events:,} events in {simulated:g} s)")
    # the same-run baseline of issue 15: every channel judged after every sample
    judged_all = Tes("TES 8EA")
    for k in range(8):
        judged_all.set_signal(k, Sine(5.0, 4.0, 1_000_000 * (k + 1)))
    ai = judged_all.ai
    ai._judge_sampled = lambda ch, now: ai.evaluate(now)  # type: ignore[method-assign]
    rate_all, _ = _measure(judged_all, simulated)
    fresh = Tes("TES 8EA")
    for k in range(8):
        fresh.set_signal(k, Sine(5.0, 4.0, 1_000_000 * (k + 1)))
    rate_one, _ = _measure(fresh, simulated)
    print(
        f"TES 8EA, 8 sine inputs, sampled channel judged: {rate_one:,.0f} vs all channels"
        f" judged: {rate_all:,.0f} simulated s per wall s ({rate_one / rate_all:.2f}x)"
    )
    idle = Tes("TES 8EA")
    idle.set_input(0, 5.0)
    rate, events = _measure(idle, 3600.0)
    print(f"TES 8EA, constant inputs: {rate:,.0f} simulated s per wall s ({events:,} events, 1 h)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
