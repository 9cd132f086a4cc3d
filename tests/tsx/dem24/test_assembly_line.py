"""The assembly line of DEM section 5: phases, oscillation thresholds, hourly global state."""

from __future__ import annotations

from fieldtwin.devices.dem24.status import details
from fieldtwin.tsx.dem24 import Dem24
from fieldtwin.tsx.plc import Plc
from tests.tsx.dem24.helpers import ASSEMBLY, SLOT, at, read_all, stamp, synced

# 5.1 table and the 5.3-4 CHART steps: (OW4,2, OW4,3) per phase
PHASES = {
    "starting": (0x0000, 0x00, set()),
    "supply": (0x00FF, 0x00, set(range(8))),
    "assembly": (0xFFFF, 0x00, set(range(16))),
    "output": (0xF000, 0x0F, set(range(12, 20))),
    "stopping": (0x0000, 0x0F, set(range(16, 20))),
}


def every_channel_once(plc: Plc, mod: Dem24) -> set[int]:
    read_all(plc)
    for channel in range(24):
        mod.set_input(channel, not mod.inputs.raw(channel))
    plc.advance(0.05)
    return {m[7] >> 8 for m in read_all(plc)}


def test_5_1_channels_logged_per_phase() -> None:
    plc, mod = synced(config=ASSEMBLY, select=0)
    for name, (ow2, ow3, logged) in PHASES.items():
        plc.write(f"OW{SLOT},2", ow2)  # CHART S(A)n: H'..' -> OW4,2 ; H'..' -> OW4,3
        plc.write(f"OW{SLOT},3", ow3)
        plc.advance(6.0)  # phases last longer than T-MAX: no input looks oscillating
        assert every_channel_once(plc, mod) == logged, name


def test_5_1_oscillating_after_more_than_3_changes_in_5_s() -> None:
    # 5.3-3: T-MAX = 5 s, N-MAX = 3: the 4th change within 5 s declares it oscillating;
    # T-MIN = 5 s, N-MIN = 2: normal again once fewer than 2 changes in 5 s.
    plc, mod = synced(config=ASSEMBLY, select=0xFFFF)
    t0 = 72.0
    for k in range(8):  # a change every second: 72, 73, ... 79 s
        at(plc, t0 + k)
        mod.set_input(6, k % 2 == 0)
    at(plc, t0 + 20)
    msgs = [m for m in read_all(plc) if m[7] >> 8 == 6]
    assert [m[7] & 0xFF for m in msgs] == [1, 0, 1, 2, 0]
    assert [stamp(m)[4:] for m in msgs[:4]] == [(6, 1, 0), (6, 2, 0), (6, 3, 0), (6, 4, 0)]
    # last changes at 78 and 79 s: fewer than 2 in 5 s from 78 + 5 = 83 s on; the
    # returning message carries the current state (0 since the change at 79 s)
    assert stamp(msgs[4])[4:] == (6, 12, 0)
    assert msgs[4][7] & 0xFF == int(mod.inputs.level(6))


def test_oscillating_input_shows_in_the_overall_state() -> None:
    plc, mod = synced(config=ASSEMBLY, select=0xFFFF)
    for k in range(4):
        at(plc, 72.0 + 0.5 * k)
        mod.set_input(9, k % 2 == 0)
    plc.advance(0.05)
    read_all(plc)
    plc.write(f"OW{SLOT},1,2", 1)
    plc.advance(0.03)
    (m,) = read_all(plc)
    assert m[9] == 1 << 9 and m[7] == 0xFFFF


def test_5_1_hourly_global_state() -> None:
    plc, mod = synced(config=ASSEMBLY, select=0, scan_ms=100)
    at(plc, 71 + 3600 * 2 + 1)
    msgs = read_all(plc)
    assert [stamp(m)[3:] for m in msgs] == [(19, 6, 0, 0), (20, 6, 0, 0)]
    assert all((m[1] >> 10) & 1 for m in msgs)
    assert plc.read(f"I{SLOT},4") == 0  # 500 ms drift allowed: no synchronization fault


def test_5_3_4_macro_step_0_initialisation() -> None:
    # XM0: stop, configure, run, set the time, purge; then IW4,5 = 0
    plc, mod = synced(config=ASSEMBLY)
    mod.set_input(0, True)
    plc.advance(0.05)
    plc.write(f"OW{SLOT},1,1", 1)
    plc.advance(0.03)
    plc.write(f"OW{SLOT},1,1", 0)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},5") == 0


def test_an_n_min_above_the_changes_that_made_it_oscillating_is_normal_again_at_once() -> None:
    """T-MAX 1 s, N-MAX 2, T-MIN 2 s, N-MIN 8: the 3rd change within 1 s makes input 6
    oscillating, and with 3 changes in 2 s (fewer than 8) it is normal again at once,
    at the instant the oscillation is declared (the check used to fall 1 us after the
    edge, already past at the confirmation: the run stopped on an error)."""
    config = [0x0014, 0, 1, 2, 2, 8, 60, 500, 60]
    plc, mod = synced(config=config, select=0xFFFF)
    for k in range(3):
        at(plc, 72.0 + 0.1 * k)
        mod.set_input(6, k % 2 == 0)
    at(plc, 73.0)  # ran on: no error
    msgs = [m for m in read_all(plc) if m[7] >> 8 == 6]
    # 1, 0, then oscillating (2), then at once normal with the present level (1)
    assert [m[7] & 0xFF for m in msgs] == [1, 0, 2, 1]
    assert stamp(msgs[2])[4:] == stamp(msgs[3])[4:]  # the same millisecond
    assert details(mod)["oscillating"] == "none"
