"""§4.1 digital behaviour in simulated time, through `fieldtwin run` and pymodbus.

The plant runs at ``SPEED`` x; expectations come from the signals' timings,
bracketed by the simulated time read back before and after (a chronometer of
an input that stays 0 counts 100 ms ticks since power-on).
"""

from __future__ import annotations

import time

import pytest
from pymodbus.client import ModbusSerialClient, ModbusTcpClient

from tests.tes.blackbox.conftest import (
    CLOCKS,
    MEMORIZED,
    NOT_READY,
    SAFETY,
    SPEED,
    WATCHDOG,
    exception_code,
    pair,
    sim_ticks,
    wait_sim,
    words,
    write,
)

FILTER_US = 5_000  # §3.1.2 factory filter, 5 ms

pytestmark = pytest.mark.timeout(30)  # every test bounded, setup included


def _rises(t_us: int, period_us: int) -> int:
    """Rising edges of a high-first pulse train, after the 5 ms filter, up to t."""
    return 0 if t_us < FILTER_US else (t_us - FILTER_US) // period_us + 1


def test_4_1_3_counters_count_the_pulse_edges(tcp: ModbusTcpClient) -> None:
    wait_sim(tcp, 3.0)
    before = sim_ticks(tcp) * 100_000
    counters = words(tcp, CLOCKS, 0x025, 0x086 - 0x025)  # rising 0..31, falling 0..15
    after = (sim_ticks(tcp) + 1) * 100_000
    rise0, rise2 = pair(*counters[0:2]), pair(*counters[4:6])
    fall0 = pair(*counters[0x065 - 0x025 : 0x067 - 0x025])
    assert _rises(before, 1_000_000) <= rise0 <= _rises(after, 1_000_000)
    assert _rises(before, 100_000) <= rise2 <= _rises(after, 100_000)
    assert rise0 - 1 <= fall0 <= rise0  # a fall follows each rise (high first)
    assert pair(*counters[2:4]) == 0  # input 1 never changes


def test_4_1_3_the_master_resets_a_counter(tcp: ModbusTcpClient) -> None:
    wait_sim(tcp, 2.0)
    write(tcp, CLOCKS, 0x025 + 2 * 2, 0, 0)  # input 2 (0.1 s pulses)
    before = sim_ticks(tcp)
    time.sleep(0.1)  # 2 simulated seconds
    after = sim_ticks(tcp)
    (hi, lo) = words(tcp, CLOCKS, 0x025 + 2 * 2, 2)
    # about one rising edge per 100 ms since the reset, never the count since power-on
    assert (after - before) - 4 <= pair(hi, lo) <= sim_ticks(tcp) - before + 2


def test_4_1_4_chronometers_of_a_1_s_pulse_train(tcp: ModbusTcpClient) -> None:
    wait_sim(tcp, 2.5)
    d = words(tcp, CLOCKS, 0x0A5, 0x0E7 - 0x0A5)  # duration of state 1 then of state 0
    d1, d0 = pair(*d[0:2]), pair(*d[0x0E5 - 0x0A5 : 0x0E7 - 0x0A5])
    # §4.1.4 the last state lasted 0.5 s (5 ticks); the running one is 0..5 ticks
    assert max(d1, d0) == 5 and min(d1, d0) <= 5
    c = words(tcp, CLOCKS, 0x125, 0x167 - 0x125)
    c1, c0 = pair(*c[0:2]), pair(*c[0x165 - 0x125 : 0x167 - 0x125])
    total = sim_ticks(tcp)
    # §4.1.4 cumulated durations: half of the time each, together the time since power-on
    assert total - 3 <= c1 + c0 <= total
    assert abs(c1 - c0) <= 6


def test_4_1_6_blinking_follows_the_blink_times_in_simulated_time(tcp: ModbusTcpClient) -> None:
    """Output 1 blinks at frequency 0 (1 Hz), output 2 at frequency 1 (10 Hz), output 0 fixed.

    The pulse trains on inputs 0 (1 s) and 2 (0.1 s) have the same period and phase
    (both start at power-on with state 1), shifted by the 5 ms filter: the filtered
    inputs and the outputs, read in one request, agree except in that 5 ms.
    """
    write(tcp, CLOCKS, 0x00C, 0x0006)  # word 0: outputs 1 and 2 blink
    write(tcp, CLOCKS, 0x00D, 0x0005)  # word 1: output 0 at 1, output 1 freq 0, 2 freq 1
    same = {1: 0, 2: 0}
    seen: dict[int, set[int]] = {1: set(), 2: set()}
    samples = 60
    for _ in range(samples):
        reply = words(tcp, CLOCKS, 0x003, 5)  # filtered inputs ... outputs state (007h)
        filtered, outputs = reply[0], reply[4]
        assert outputs & 1  # fixed at 1
        for bit in (1, 2):
            out = (outputs >> bit) & 1
            seen[bit].add(out)
            same[bit] += out == (filtered >> (0 if bit == 1 else 2)) & 1
        time.sleep(0.013)
    assert seen == {1: {0, 1}, 2: {0, 1}}
    assert same[1] >= samples - 6 and same[2] >= samples * 0.75


def test_4_1_2_memorized_changes_are_restored_one_per_read(line_a: ModbusSerialClient) -> None:
    # input 1 changed 5 times (1.0 .. 1.5 s): 0 -> 1 -> 0 -> 1 -> 0 -> 1
    deadline = time.monotonic() + 5
    while not words(line_a, MEMORIZED, 0x003)[0] & 2:
        assert time.monotonic() < deadline
        time.sleep(0.02)
    time.sleep(0.05)  # the last edge is past its filter
    assert words(line_a, MEMORIZED, 0x000)[0] & 0x08  # §6.2.1 bit 3: changes to read
    memorized = [words(line_a, MEMORIZED, 0x001)[0] >> 1 & 1 for _ in range(7)]
    assert memorized == [1, 0, 1, 0, 1, 1, 1]  # each read restores one change, then holds
    assert not words(line_a, MEMORIZED, 0x000)[0] & 0x08  # reset by the TES


def test_4_1_7_watchdog_fallback_and_recovery(tcp: ModbusTcpClient) -> None:
    slave = WATCHDOG
    write(tcp, slave, 0x00C, 0x0000, 0x00F0)  # outputs 4..7 on, fixed
    write(tcp, slave, 0x012, 0x0001, 0x0002, 0xFFFF, 0x000F)  # OR and AND masks
    write(tcp, slave, 0x000, 0x0000)
    write(tcp, slave, 0x016, 40)  # 4 s of master silence (Tb = 100 ms)
    for _ in range(8):  # a request every ~0.5 simulated s keeps the outputs
        time.sleep(0.5 / SPEED)
        assert words(tcp, slave, 0x000)[0] & 0x02 == 0
    # silence for 6 simulated s; other slaves' traffic does not re-arm it (AMB-TES-10)
    start = sim_ticks(tcp)
    deadline = time.monotonic() + 6.0 / SPEED * 3 + 5
    while sim_ticks(tcp) < start + 60:
        assert time.monotonic() < deadline
        time.sleep(0.01)
    status, *_ = words(tcp, slave, 0x000)
    outputs, *_ = words(tcp, slave, 0x007)
    assert status & 0x02  # §6.2.1 bit 1: fallback
    # AMB-TES-11 (command AND and-mask) OR or-mask: blink 0001h, state 00F0h & 000Fh | 0002h
    assert words(tcp, slave, 0x00C, 2) == [0x0001, 0x0002]
    assert outputs & ~1 == 0x0002 & ~1
    write(tcp, slave, 0x00C, 0x0000, 0x0300)  # recovery: the master commands again
    write(tcp, slave, 0x000, 0x0000)
    assert words(tcp, slave, 0x007) == [0x0300]
    assert words(tcp, slave, 0x000)[0] & 0x02 == 0
    write(tcp, slave, 0x016, 0)


def test_amb_tes_28_not_ready_in_the_32_bit_area_only(tcp: ModbusTcpClient) -> None:
    codes = set()
    for _ in range(60):
        reply = tcp.read_holding_registers(0x025, count=2, device_id=NOT_READY)
        codes.add(exception_code(reply) if reply.isError() else 0)
        if codes == {0, 4}:
            break
        time.sleep(0.002)
    assert codes == {0, 4}  # refused in the 50 ms window of each 100 ms refresh
    for _ in range(20):  # below 025h: never refused
        assert not tcp.read_holding_registers(0x003, count=2, device_id=NOT_READY).isError()
    assert words(tcp, NOT_READY, 0x018)[0] >= 1  # counted as "slave not ready" replies


def test_6_2_7_short_and_open_circuits_of_the_32et_s(tcp: ModbusTcpClient) -> None:
    assert words(tcp, SAFETY, 0x1A5, 6) == [0] * 6  # no input wired in security mode yet
    write(tcp, SAFETY, 0x000, 0x0000)
    assert words(tcp, SAFETY, 0x000)[0] & 0x04 == 0
    write(tcp, SAFETY, 0x1AB, 0x0088)  # inputs 3 and 7 (E4, E8) in security mode
    sc, _, oc, _, default, _ = words(tcp, SAFETY, 0x1A5, 6)
    assert (sc, oc, default) == (0x0008, 0x0080, 0x0088)
    assert words(tcp, SAFETY, 0x000)[0] & 0x04  # §6.2.1 bit 2
    assert words(tcp, SAFETY, 0x005)[0] & 0x88 == 0x08  # short reads 1, broken wire 0
