"""Periodic overall-state logging (DEM 3.2-1 PER) timed by the module's own clock."""

from __future__ import annotations

from fieldtwin.clock import S
from fieldtwin.facade import inject_fault
from tests.tsx.dem24.helpers import at, read_all, stamp, synced

# LOG, T-SYN 60 s, DRIFT 500 ms (no drift fault at 100 ppm), PER 1 min
PER_1 = [0x0010, 0, 0, 0, 0, 0, 60, 500, 1]


def test_3_2_1_per_counts_module_minutes_while_the_clock_runs_free() -> None:
    # 2.5-6: in a synchronization fault the module goes on with its internal clock;
    # 100 ppm fast, the module minute ends 6 ms early in simulated time each minute.
    plc, mod = synced(config=PER_1)  # 18:06:00.000 at t = 71 s
    inject_fault(mod, "pulses", True)
    mod.set_clock_drift(100.0)
    at(plc, 250.97)  # module 18:08:59.988
    assert len(mod.stack) == 3  # 18:07, 18:08 overall; channel 24 (loss at 131.5 s)
    at(plc, 250.99)  # module 18:09:00.000 reached at 71 + 180 / 1.0001 = 250.982 s
    msgs = read_all(plc)
    overall = [stamp(m)[4:] for m in msgs if (m[1] >> 10) & 1]
    assert overall == [(7, 0, 0), (8, 0, 0), (9, 0, 0)]
    assert [m[7] for m in msgs if not (m[1] >> 10) & 1] == [(24 << 8) | 1]


def test_3_2_1_per_on_whole_module_minutes_with_pulses_resetting_a_fast_clock() -> None:
    plc, mod = synced(config=PER_1)
    mod.set_clock_drift(-20.0)  # slow: each pulse puts the clock 1.2 ms forward
    at(plc, 71 + 5 * 60 + 0.5)
    msgs = read_all(plc)
    assert [stamp(m)[4:] for m in msgs] == [(7, 0, 0), (8, 0, 0), (9, 0, 0), (10, 0, 0), (11, 0, 0)]
    assert all((m[1] >> 10) & 1 for m in msgs) and plc.read("I4,4") == 0
    assert plc.now > 371 * S
