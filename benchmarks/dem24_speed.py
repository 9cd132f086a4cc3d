"""How many input edges a DEM 2412 time-stamps per wall second.

24 channels driven by random edges (channels 0..11 every 20 ms on average, so they
go oscillating; 12..23 every 1.5 s, logged, now and then oscillating), oscillation
detection on, 10 ms PLC scan, messages read by the module API every simulated second
so the stack never saturates.
Prints edges time-stamped, messages logged and their rates per CPU second of this
process and per wall second, with the event-driven bus refresh (the default) and,
as the baseline in the same run, the full refresh of every slot at every task.

    python benchmarks/dem24_speed.py [--counts]

``--counts`` also prints the instructions per time-stamped edge of the event-driven
run (benchmarks/counts.py: perf or callgrind, a fixed workload of 5 and 25 simulated
seconds after the set-up, in fresh processes), which the machine's load does not move.
"""

from __future__ import annotations

import argparse
import time

from fieldtwin.clock import S
from fieldtwin.devices.dem24.status import details
from fieldtwin.signals import RandomEdges
from fieldtwin.tsx.dem24.module import Dem24
from fieldtwin.tsx.plc import Plc

SIM_SECONDS = 120
CONFIG = [0x0014, 0, 5, 9, 5, 2, 60, 500, 1]  # OSC + LOG, FILT 0, 9 in 5 s / 2 in 5 s


def setup(event_driven: bool) -> tuple[Plc, Dem24]:
    plc = Plc(model="TSX 87", scan_ms=10, event_driven=event_driven)
    mod = plc.insert("TSX DEM 2412", rack=0, slot=4, code=777)
    plc.advance(10.1)
    plc.write("OW4,0,C", 0)
    plc.advance(0.03)
    assert plc.exchange(m=0x0463, c=0x40, send=CONFIG).v == 0xFE
    plc.write("OW4,0,C", 1)
    plc.write("OW4,2", 0xFFFF)
    plc.write("OW4,3", 0x00FF)
    mod.attach_pulse_source(60 * S, 11 * S)
    plc.advance(1.0)
    plc.exchange(m=0x0400, c=0x02, send=[0x5E07, 0x0F12, 0x0521, 0x0001])
    for channel in range(24):
        mean = 20_000 if channel < 12 else 1_500_000  # 0..11 chatter, 12..23 logged
        mod.set_signal(channel, RandomEdges(seed=channel, mean_interval_us=mean))
    plc.advance(60.0)  # the time is taken at the pulse at 71 s
    return plc, mod


def workload(sim_s: int) -> None:
    """The counted work: the event-driven module, ``sim_s`` simulated seconds."""
    plc, mod = setup(True)
    stamped0 = mod.edges_stamped
    for _ in range(sim_s):
        plc.advance(1.0)
        mod.read_messages(len(mod.stack))
    print(f"units {mod.edges_stamped - stamped0}")


def run(event_driven: bool) -> tuple[float, float, int]:
    plc, mod = setup(event_driven)
    stamped0, stored0 = mod.edges_stamped, mod.stack.total_stored
    events0 = plc.clock.fired
    cpu, start = time.process_time(), time.perf_counter()
    for _ in range(SIM_SECONDS):
        plc.advance(1.0)
        mod.read_messages(len(mod.stack))
    wall = time.perf_counter() - start
    cpu = time.process_time() - cpu
    edges = mod.edges_stamped - stamped0
    messages = mod.stack.total_stored - stored0
    name = "event-driven refresh" if event_driven else "full refresh (baseline)"
    print(f"{name}: simulated {SIM_SECONDS} s in {cpu:.2f} s CPU, {wall:.2f} s wall")
    print(f"  input edges time-stamped: {edges} ({edges / cpu:,.0f} per CPU second,")
    print(f"  {edges / wall:,.0f} per wall second); messages logged: {messages}")
    print(f"  clock events: {plc.clock.fired - events0}; lost messages: {mod.stack.total_lost}")
    print(f"  oscillating channels at the end: {details(mod)['oscillating']}")
    return edges / cpu, edges / wall, messages


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", action="store_true", help="also instructions per edge")
    parser.add_argument("--workload", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.workload is not None:
        workload(args.workload)
        return
    cpu, wall, messages = run(True)
    cpu0, wall0, messages0 = run(False)
    assert messages == messages0, "the two refreshes logged differently"
    print(f"edges per CPU second: {cpu:,.0f} against {cpu0:,.0f} ({cpu / cpu0:.2f}x)")
    print(f"edges per wall second: {wall:,.0f} against {wall0:,.0f} ({wall / wall0:.2f}x)")
    if args.counts:
        from counts import per_unit

        print("event-driven refresh:", per_unit(__file__, 5, 25, "edge"), flush=True)


if __name__ == "__main__":
    main()
