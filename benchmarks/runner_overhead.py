"""How many clock events per wall second the runner processes when not paced.

Cases, all measured in the same run (ratios are against the first):
  * no transports        - Runner.advance is exactly SimClock.advance
  * one memory transport - polled after every instant
  * memory + pty         - plus a zero-timeout select of the pty between instants

Usage: .venv/bin/python benchmarks/runner_overhead.py [events]
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

from fieldtwin.clock import SimClock
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.memory import memory_pair
from fieldtwin.transports.pty import open_pty

PERIOD_US = 100  # one event every 100 us of simulated time


def _measure(events: int, attach: Callable[[Runner], Callable[[], None]]) -> float:
    """Events per wall second for ``events`` periodic events; ``attach`` returns a cleanup."""
    clock = SimClock()
    runner = Runner(clock, speed=None)
    cleanup = attach(runner)

    def periodic(now: int) -> None:
        clock.call_later(PERIOD_US, periodic)

    clock.schedule(PERIOD_US, periodic)
    start = time.perf_counter()
    runner.advance(events * PERIOD_US)
    elapsed = time.perf_counter() - start
    cleanup()
    assert clock.fired == events, clock.fired
    return events / elapsed


def _nothing(runner: Runner) -> Callable[[], None]:
    return lambda: None


def _memory(runner: Runner) -> Callable[[], None]:
    a, b = memory_pair()
    runner.attach(a, lambda data, now: None)

    def close() -> None:
        a.close()
        b.close()

    return close


def _memory_and_pty(runner: Runner) -> Callable[[], None]:
    cleanup = _memory(runner)
    pty = open_pty()
    runner.attach(pty, lambda data, now: None)

    def close() -> None:
        cleanup()
        pty.close()

    return close


def main() -> None:
    events = int(sys.argv[1]) if len(sys.argv) > 1 else 200_000
    cases = [
        ("no transports (plain clock)", _nothing),
        ("one memory transport", _memory),
        ("one memory + one pty transport", _memory_and_pty),
    ]
    print(f"runner overhead, not paced (speed=None), {events} events, one every {PERIOD_US} us")
    baseline = 0.0
    for label, attach in cases:
        rate = max(_measure(events, attach) for _ in range(3))  # best of three
        baseline = baseline or rate
        print(f"  {label:34s} {rate:14,.0f} events/s   x{rate / baseline:.3f}")


if __name__ == "__main__":
    main()
