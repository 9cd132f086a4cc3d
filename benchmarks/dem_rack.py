"""A TSX 87 full of time-stamping modules on one synchronization output, all logging.

32 TSX DEM 2412 (the most one PLC configuration takes, DEM 6.2-2) in racks 0..3:
the first has a 30 s pulse generator on IN-SYN and its OUT-SYN drives the 31
others (DEM 7.2, at most 32 on one output); each is configured to log (LOG, FILT 10 ms,
T-SYN 30 s), has its time set (request 2) and 4 of its channels driven by random
edges (one every 2 s on average each), so that every module logs all the time; the
messages are read every simulated second through the module API.

The same rack runs twice in this process: with the event-driven bus refresh (the
default) and with the full refresh of every slot at every task (the baseline).
Prints speed factors over real time (simulated s per CPU s and per wall s), the
edges time-stamped and the messages logged, and the gain.

    python benchmarks/dem_rack.py [simulated seconds, default 60] [--counts]

``--counts`` also prints the instructions per simulated second of the event-driven
rack (benchmarks/counts.py: perf or callgrind, a fixed workload of 5 and 25 simulated
seconds after the set-up), which the machine's load does not move.
"""

from __future__ import annotations

import argparse
import sys
import time

from fieldtwin.clock import S
from fieldtwin.signals import RandomEdges
from fieldtwin.tsx.dem24.module import Dem24
from fieldtwin.tsx.plc import Plc

MODULES = 32
CONFIG = [0x0010, 10, 0, 0, 0, 0, 30, 10, 1]  # LOG, FILT 10 ms, T-SYN 30 s, PER 1 min
TIME = [0x5E07, 0x0F12, 0x0521, 0x0001]  # DEM 4.1-2 example: 15 July 1994 18:05:33


def m_of(module: Dem24, zz: int) -> int:
    return (module.rack << 12) | (module.slot << 8) | zz


def build(event_driven: bool) -> tuple[Plc, list[Dem24]]:
    plc = Plc(model="TSX 87", scan_ms=10, event_driven=event_driven)
    mods: list[Dem24] = []
    for k in range(MODULES):
        module = plc.insert("TSX DEM 2412", rack=k // 8, slot=k % 8, code=777)
        assert isinstance(module, Dem24)
        mods.append(module)
    for other in mods[1:]:
        mods[0].connect_sync_output(other)
    plc.advance(10.1)  # the self-tests
    for module in mods:
        assert plc.exchange(m=m_of(module, 0x63), c=0x40, send=CONFIG).v == 0xFE
    for module in mods:
        address = module.address
        plc.write(f"OW{address},0,C", 1)
        plc.write(f"OW{address},2", 0x000F)  # channels 0..3 time-stamped
    mods[0].attach_pulse_source(30 * S, plc.now + 5 * S)
    for module in mods:
        plc.exchange(m=m_of(module, 0x00), c=0x02, send=TIME)
    plc.advance(40.0)  # the time is taken at the next pulse
    assert all(m.logbook.timebase.ready for m in mods), "a module has no time"
    for n, module in enumerate(mods):
        for channel in range(4):
            seed = 100 * n + channel
            module.set_signal(channel, RandomEdges(seed=seed, mean_interval_us=2 * S))
    plc.advance(2.0)
    return plc, mods


def run(event_driven: bool, sim_s: int) -> tuple[float, float, int, int]:
    plc, mods = build(event_driven)
    stamped = sum(m.edges_stamped for m in mods)
    stored = sum(m.stack.total_stored for m in mods)
    cpu, wall = time.process_time(), time.perf_counter()
    for _ in range(sim_s):
        plc.advance(1.0)
        for module in mods:
            module.read_messages(len(module.stack))
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    edges = sum(m.edges_stamped for m in mods) - stamped
    messages = sum(m.stack.total_stored for m in mods) - stored
    assert sum(m.stack.total_lost for m in mods) == 0
    return sim_s / cpu, sim_s / wall, edges, messages


def workload(sim_s: int) -> None:
    """The counted work: the event-driven rack, ``sim_s`` simulated seconds."""
    plc, mods = build(True)
    for _ in range(sim_s):
        plc.advance(1.0)
        for module in mods:
            module.read_messages(len(module.stack))
    print(f"units {sim_s}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sim_s", nargs="?", type=int, default=60, help="simulated seconds")
    parser.add_argument("--counts", action="store_true", help="also instructions per sim s")
    parser.add_argument("--workload", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.workload is not None:
        workload(args.workload)
        return 0
    sim_s = args.sim_s
    print(f"TSX 87, {MODULES} DEM 2412 on one sync output, all logging; {sim_s} simulated s")
    print(f"{'bus refresh':<14} {'cpu':>9} {'wall':>9} {'edges':>8} {'messages':>9}")
    results = {}
    for event_driven in (True, False):
        cpu, wall, edges, messages = run(event_driven, sim_s)
        name = "event-driven" if event_driven else "full (baseline)"
        print(f"{name:<14} {cpu:>8,.0f}x {wall:>8,.0f}x {edges:>8} {messages:>9}")
        results[event_driven] = (cpu, edges, messages)
    assert results[True][1:] == results[False][1:], "the two refreshes logged differently"
    print(f"gain (cpu): {results[True][0] / results[False][0]:.2f}; same edges and messages")
    if args.counts:
        from counts import per_unit

        print("event-driven:", per_unit(__file__, 5, 25, "simulated second"), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
