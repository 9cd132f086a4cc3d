"""Master-task cycles per second of the manuals' PL7-3 programs (fieldtwin.pl7).

The AEM 5.1 tank application and the DEM 5.3-4 assembly line run against the
in-memory ProgramMemory; a small script answers their Text Blocks as the module
would, so that the programs reach their steady state (measurement processing for
the tanks, step 0..4 of the chart for the assembly line) before they are timed.

Each is timed twice in the same run: skipping the master tasks that are fixed
points (the default, fieldtwin/pl7/watch.py) and running every task
(``skip_idle = False``, the baseline); on the twin PLC, the baseline is also the
full bus refresh (``Plc.event_driven = False``).  Rates are per CPU second of this
process (the figure to compare on a shared machine).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from fieldtwin.pl7 import Executor, InMemory, parse

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
CYCLES = 20_000


def answer(memory: InMemory, done: int, v: int = 0xFE) -> int:
    for started in memory.started[done:]:
        memory.finish(started.index, v=v)
    return len(memory.started)


def tank() -> tuple[Executor, InMemory]:
    memory = InMemory()
    executor = Executor(parse((EXAMPLES / "aem811_tank.pl7").read_text()), memory)
    aem = memory.module(0, 5)
    aem.iw[0], aem.iw[2] = 1 << 3, 1 << 0xD
    memory.module(1, 4).i[0] = 1
    done = 0
    for _ in range(10):
        executor.run_master_task()
        aem.iw[2] &= ~(1 << 0xD)
        aem.iw[0] = (aem.iw[0] & ~(1 << 0xC)) | (aem.ow[0] & (1 << 0xC))
        done = answer(memory, done)
    assert memory.b[3] == 1, "the tank program did not reach measurement processing"
    aem.iw[3:7] = [1000, 2000, 3000, 4000]
    return executor, memory


def assembly() -> tuple[Executor, InMemory]:
    memory = InMemory()
    executor = Executor(parse((EXAMPLES / "dem24_assembly.pl7").read_text()), memory)
    dem = memory.module(0, 4)
    done = 0
    for _ in range(10):
        executor.run_master_task()
        dem.iw[0] = (dem.iw[0] & ~(1 << 0xC)) | (dem.ow[0] & (1 << 0xC))
        done = answer(memory, done)
    assert executor.active_steps() == ["0"], executor.active_steps()
    return executor, memory


def measure(name: str, executor: Executor, memory: InMemory, toggle: bool) -> None:
    inputs = memory.module(0, 2).i
    rates = []
    for skip in (True, False):
        executor.skip_idle = skip
        start = time.process_time()
        for k in range(CYCLES):
            if toggle:
                inputs[k % 5] = 1  # the operator inputs walk the chart through its phases
                inputs[(k - 1) % 5] = 0
            executor.run_master_task(k * 10_000)
        rates.append(CYCLES / (time.process_time() - start))
    # a 10 ms master task: how many times faster than real time this program can run
    print(
        f"{name:<28} {rates[0]:>10,.0f} master tasks/s  ({rates[0] / 100:,.0f} x real time"
        f" at 10 ms; every task run: {rates[1]:,.0f}/s, gain {rates[0] / rates[1]:.2f})"
    )


def on_the_plc(name: str, plant_file: Path | None, seconds: float) -> None:
    """The program in the twin PLC with its modules (bus refresh, Text Blocks, module
    cores): master tasks per CPU second, and the factor over real time."""
    from fieldtwin.plant import load_plant

    figures = []
    for event_driven in (True, False):
        plant = load_plant(plant_file, speed=None)
        try:
            plc = plant.plc
            assert plc is not None and plc.program is not None
            plc.event_driven = event_driven
            plc.advance(12.0)  # past the self-tests and the configuration
            cycles, skipped = plc.program.cycles, plc.program.skipped
            start = time.process_time()
            plc.advance(seconds)
            elapsed = time.process_time() - start
            ran = plc.program.cycles - cycles
            figures.append((ran / elapsed, seconds / elapsed, plc.program.skipped - skipped, ran))
        finally:
            plant.close()
    (rate, factor, skipped, ran), (_, factor0, _, _) = figures
    print(
        f"{name:<28} {rate:>10,.0f} master tasks/s  ({factor:,.0f} x real time, {skipped}"
        f" of {ran} tasks skipped; full: {factor0:,.0f} x, gain {factor / factor0:.2f})"
    )


def main() -> int:
    print(f"fieldtwin.pl7, {CYCLES} master tasks each, in-memory ProgramMemory")
    measure("AEM 5.1 tank application", *tank(), toggle=False)
    measure("DEM 5.3-4 assembly line", *assembly(), toggle=True)
    print("the twin PLC with its modules (--speed max, one core), per CPU second")
    on_the_plc("AEM 5.1 tank plant", EXAMPLES / "aem811_tank.toml", 120.0)
    on_the_plc("DEM 5.3-4 assembly plant", EXAMPLES / "dem24_assembly.toml", 120.0)
    on_the_plc("default plant (AEM program)", None, 120.0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
