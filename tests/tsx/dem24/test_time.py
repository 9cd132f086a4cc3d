"""Setting the module time (DEM 2.3-1, 4.1) and synchronization faults (4.1-3, 2.5-6)."""

from __future__ import annotations

import pytest

from fieldtwin.clock import S
from fieldtwin.errors import ConfigError
from fieldtwin.facade import inject_fault
from fieldtwin.tsx.plc import Plc
from tests.tsx.dem24.helpers import (
    JULY_15_1994,
    SLOT,
    at,
    configure,
    make,
    read,
    read_all,
    send_time,
    stamp,
    synced,
)

T30 = [0, 0, 0, 0, 0, 0, 30, 2, 0]


def test_4_1_3_example_time_taken_at_the_next_30_s_pulse() -> None:
    # "Time reference: 15 July 1994 at 18h 5min 33 sec ... The time picked up on the
    # next pulse is: 15 July 94 18h 06min 00 sec."
    plc, mod = make()
    assert configure(plc, T30).v == 0xFE
    mod.attach_pulse_source(30 * S, 11 * S)
    plc.write(f"OW{SLOT},2", 0x0008)
    at(plc, 11.5)  # pulse at 11 s: the module has its period reference
    r = send_time(plc, JULY_15_1994)
    assert (r.v, r.e, r.s) == (0xFE, False, 0)
    at(plc, 40.9)  # no pulse yet
    assert plc.read(f"I{SLOT},0") == 0 and plc.read(f"IW{SLOT},2,7") == 0
    at(plc, 41.02)  # pulse at 41 s
    assert plc.read(f"I{SLOT},0") == 1 and plc.read(f"IW{SLOT},2,7") == 1
    first = read(plc).messages
    assert len(first) == 1
    assert (first[0][1] >> 10) & 1 == 1  # DEM 4.2-3: first message = overall state
    assert stamp(first[0]) == (94, 7, 15, 18, 6, 0, 0)
    assert first[0][1] & 0xFF == 1  # modification indicator
    at(plc, 41 + 1.234)
    mod.set_input(3, True)
    plc.advance(0.01)
    (msg,) = read(plc).messages
    assert stamp(msg) == (94, 7, 15, 18, 6, 1, 234)
    assert msg[7] == (3 << 8) | 1


def test_2_3_1_after_power_up_a_second_pulse_is_required() -> None:
    plc, mod = make()
    configure(plc, T30)
    send_time(plc, JULY_15_1994)  # before any pulse since power-up
    mod.attach_pulse_source(30 * S, 11 * S)
    at(plc, 11.01)
    assert not mod.timebase.ready  # the first pulse only starts the period
    plc.advance(30.0)
    assert mod.timebase.ready
    (msg,) = read_all(plc)
    # the time due at the first pulse (18:06:00) plus the 30 s between the two pulses
    assert stamp(msg) == (94, 7, 15, 18, 6, 30, 0)


def test_4_1_2_refused_time_is_fd_and_fault_bit_34() -> None:
    plc, mod = make()
    r = send_time(plc, [0x5E0D, 0x0F12, 0x0521, 0x0001])  # month 13
    assert r.v == 0xFD
    plc.advance(0.02)
    assert mod.leds["ERR"] == "on" and plc.read(f"IW{SLOT},0,7") == 1
    fault = plc.exchange(m=0x0463, c=0x47, recv_bytes=12)
    assert fault.v == 0x77 and fault.s == 12 and fault.data[4] == 0x04  # bit 34
    assert send_time(plc, [0x5F02, 0x1D00, 0, 1]).v == 0xFD  # 29 Feb 1995: not leap
    assert send_time(plc, [0x6002, 0x1D00, 0, 1]).v == 0xFE  # 29 Feb 1996: leap
    assert send_time(plc, [0x5E07, 0x0F12, 0x0521]).v == 0xFD  # 6 bytes, 8 required


def test_pulse_image_toggles_at_each_pulse() -> None:
    # DEM 2.4-2 note: "The state of Ixy,7 changes at each pulse"
    plc, mod = make()
    seen = []
    for _ in range(3):
        mod.sync_pulse()
        plc.advance(0.02)
        seen.append(plc.read(f"I{SLOT},7"))
    assert seen == [1, 0, 1]


def test_drift_fault_and_its_clearing_two_pulses_after_a_new_time() -> None:
    # DEM 4.1-3: a drift above DRIFT is a synchronization fault; "the fault will
    # disappear two synchronization pulses after time reception".
    plc, mod = synced()  # 60 s pulses at 11 + 60 k s; 18:06:00 taken at 71 s
    mod.set_clock_drift(100.0)  # 6 ms per minute against DRIFT = 2 ms
    at(plc, 131.01)
    assert plc.read(f"I{SLOT},4") == 1 and mod.leds["ERR"] == "on"
    assert plc.read(f"IW{SLOT},0,7") == 1 and mod.running  # application fault: stays in RUN
    (msg,) = read_all(plc)
    assert msg[7] == (24 << 8) | 1 and (msg[1] >> 8) & 1 == 1  # channel 24, H = 1
    mod.set_clock_drift(0.0)
    plc.advance(60.0)  # no new time: the fault stays even though the clock is now good
    assert plc.read(f"I{SLOT},4") == 1
    send_time(plc, [0x5E07, 0x0F12, 0x0830, 0x0001])  # 18:08:30 -> due at the next pulse
    at(plc, 251.01)  # first pulse after reception: time taken
    assert plc.read(f"I{SLOT},4") == 1
    plc.advance(60.0)  # second pulse: the fault disappears
    assert plc.read(f"I{SLOT},4") == 0 and mod.leds["ERR"] == "off"
    messages = read_all(plc)
    cleared = [m for m in messages if m[7] >> 8 == 24]
    assert [m[7] & 0xFF for m in cleared] == [0]
    assert stamp(cleared[0]) == (94, 7, 15, 18, 10, 0, 0)
    assert (cleared[0][1] >> 8) & 1 == 0


def test_25_ppm_clock_stays_within_a_2_ms_drift() -> None:
    # DEM 2.1-2: 25 ppm; 60 s -> 1.5 ms between pulses, under the 2 ms default
    plc, mod = synced()
    mod.set_clock_drift(25.0)
    plc.advance(600.0)
    assert plc.read(f"I{SLOT},4") == 0


def test_loss_of_pulses_is_a_synchronization_fault() -> None:
    plc, mod = synced()
    assert mod.pulse_source is not None
    inject_fault(mod, "pulses", True)
    at(plc, 131.001)
    assert plc.read(f"I{SLOT},4") == 0  # T-SYN + DRIFT not yet over
    plc.advance(0.01)  # 71 s + 60 s + 2 ms
    assert plc.read(f"I{SLOT},4") == 1
    (msg,) = read_all(plc)
    assert msg[7] == (24 << 8) | 1 and stamp(msg) == (94, 7, 15, 18, 7, 0, 2)


def test_modification_indicator_takes_a_new_time_without_a_drift_fault() -> None:
    # DEM 4.1-3: summer/winter time: a new indicator resets the module without the check
    plc, mod = synced()
    send_time(plc, [0x5E07, 0x0F11, 0x0700, 0x0002])  # one hour back, indicator 2
    at(plc, 131.01)
    assert plc.read(f"I{SLOT},4") == 0
    (msg,) = read_all(plc)
    assert stamp(msg) == (94, 7, 15, 17, 7, 0, 0) and msg[1] & 0xFF == 2


def test_same_indicator_with_a_jump_is_a_drift_fault() -> None:
    plc, mod = synced()
    send_time(plc, [0x5E07, 0x0F11, 0x0700, 0x0001])  # one hour back, same indicator
    at(plc, 131.01)
    assert plc.read(f"I{SLOT},4") == 1


def test_sync_output_drives_other_modules() -> None:
    # DEM 1.2-1: "The module transmits a synchronization pulse to other modules"
    plc, a = make()
    b = plc.insert("TSX DEM 2412", rack=0, slot=5)
    plc.advance(10.1)
    a.connect_sync_output(b)
    a.sync_pulse()
    plc.advance(0.02)
    assert plc.read(f"I{SLOT},7") == 1 and plc.read("I5,7") == 1


def test_5_3_4_post_program_time_setting_from_the_w_table() -> None:
    # L12: SHL 8(SW56 REM 100) OR SW55 -> W200 ... INC W203; H'FF' AND W203 -> W203;
    # H'400' -> Txt_2,M; 2 -> Txt_2,C; 0 -> Txt_2,L; EXCHG Txt_2 (AMB-DEM-15)
    plc, mod = make()
    for word, value in zip(range(200, 204), JULY_15_1994, strict=True):
        plc.write(f"W{word}", value)
    refused = plc.exchange(m=0x0400, c=0x02, table=200, length=0)  # as printed
    assert refused.v == 0xFD  # no time table reaches the module
    fault = plc.exchange(m=0x0463, c=0x47, recv_bytes=12)
    assert fault.data[4] & 0x04  # bit 34 time reference refused: ERR, IWxy,0,7
    assert plc.exchange(m=0x0400, c=0x02, table=200, length=8).v == 0xFE  # W200(4)
    assert mod.timebase.pending is not None
    assert mod.timebase.pending.time.minute == 5 and mod.timebase.pending.indicator == 1


def test_7_2_sync_output_drives_at_most_32_modules() -> None:
    plc, source = make()
    # DEM 6.2-2: 32 time-stamping modules a PLC, so the followers are in two other PLCs
    others = [Plc(clock=plc.clock), Plc(clock=plc.clock)]
    followers = [
        others[k // 32].insert("TSX DEM 2412", rack=k % 32 // 8, slot=k % 8) for k in range(33)
    ]
    for follower in followers[:32]:
        source.connect_sync_output(follower)
    with pytest.raises(ConfigError, match="at most 32"):
        source.connect_sync_output(followers[32])
