"""§4.2 / §4.3 analog behaviour in simulated time, through `fieldtwin run` and pymodbus.

TES 8EA (slave ANALOG) inputs: a0 5 V, a1 ramp 0..10 V over 100 s, a2 10 V
scaled -100..15000, a3 and a4 a 0/10 V square of 1 s averaged on 256 and on
2 samples, a5..a7 a 0..10 V sine of 4 s with thresholds set on line.
"""

from __future__ import annotations

import time

import pytest
from pymodbus.client import ModbusSerialClient, ModbusTcpClient

from fieldtwin.words import to_signed
from tests.tes.blackbox.conftest import ANALOG, ANALOG_WDG, sim_ticks, wait_sim, words, write

HISTORY = 87  # §6.4.13 history of input k from 87 + 121 k (AMB-TES-14)

pytestmark = pytest.mark.timeout(30)  # every test bounded, setup included


def test_4_2_4_points_and_scaling(tcp: ModbusTcpClient) -> None:
    wait_sim(tcp, 1.0)
    a0, _, a2 = words(tcp, ANALOG, 0x003, 3)
    assert a0 == 512  # 5 V of 10 V in 0..1023 points (AMB-TES-18: rounded)
    assert to_signed(a2) == 15000  # 1023 points scaled to -100..15000


def test_4_2_3_filtering_on_256_and_on_2_samples(tcp: ModbusTcpClient) -> None:
    wait_sim(tcp, 20.0)  # 256 samples of 64 ms (§4.2.1, 8 channels) fill in 16.4 s
    seen = set()
    for _ in range(20):
        a3, a4 = words(tcp, ANALOG, 0x006, 2)
        assert 511 - 40 <= a3 <= 512 + 40  # the average of a 50 % square
        seen.add(a4)
        time.sleep(0.01)
    assert seen <= {0, 512, 1023} and {0, 1023} <= seen


def test_4_2_2_history_every_second_newest_first(tcp: ModbusTcpClient) -> None:
    ticks = wait_sim(tcp, 12.0)
    h0 = words(tcp, ANALOG, HISTORY, 120)
    h1 = words(tcp, ANALOG, HISTORY + 121, 120)
    stored = sum(1 for v in h0 if v)
    assert ticks // 10 - 2 <= stored <= min(120, ticks // 10 + 2)  # one per simulated second
    assert h0[:stored] == [512] * stored
    # the ramp climbs 10.23 points a second: newest at the lowest address
    steps = [h1[j] - h1[j + 1] for j in range(min(stored, 110) - 2)]
    assert steps and all(8 <= s <= 12 for s in steps), steps


def test_4_2_6_thresholds_bits_and_reflex_outputs(tcp: ModbusTcpClient) -> None:
    write(tcp, ANALOG, 0x023 + 5, 300, 300, 300)  # low thresholds of a5, a6, a7
    write(tcp, ANALOG, 0x02B + 5, 700, 700, 700)  # high thresholds
    # AMB-TES-21 high byte: output of the high threshold, low byte: of the low one
    write(tcp, ANALOG, 0x033 + 5, 0x0100, 0x0202, 0x03FF)  # high/low, hysteresis, high only
    write(tcp, ANALOG, 0x03B, 0x0008)  # output 3 reversed
    write(tcp, ANALOG, 0x000, 0x0000)
    time.sleep(0.2)  # re-evaluated at the next acquisitions
    lows = highs = 0
    for _ in range(80):
        r = words(tcp, ANALOG, 0x003, 0x01D - 0x003)  # one request: one simulated instant
        values, states, outputs = r[0:8], r[8:16], r[0x01C - 0x003] >> 8
        for k in (5, 6, 7):
            v = to_signed(values[k])
            assert bool(states[k] & 0x10) == (v < 300), (k, v, states[k])  # §6.4.4 bit 4
            assert bool(states[k] & 0x20) == (v > 700), (k, v, states[k])  # bit 5
        v5, v6, v7 = (to_signed(values[k]) for k in (5, 6, 7))
        assert outputs & 1 == (v5 < 300) and (outputs >> 1) & 1 == (v5 > 700)  # §4.2.6.3
        if v6 > 700 or v6 < 300:
            assert (outputs >> 2) & 1 == (v6 > 700)  # §4.2.6.2 set above, reset under
        assert (outputs >> 3) & 1 == (not v7 > 700)  # reversed polarity
        lows += v5 < 300
        highs += v5 > 700
        time.sleep(0.005)
    assert lows and highs
    status = words(tcp, ANALOG, 0x000)[0]
    assert status & 0xC0 == 0xC0  # §6.4.1 bits 6 and 7 latched until the master resets them
    write(tcp, ANALOG, 0x033 + 5, 0xFFFF, 0xFFFF, 0xFFFF)  # no output any more


def test_6_4_11_analog_fallback_and_recovery(
    line_a: ModbusSerialClient, tcp: ModbusTcpClient
) -> None:
    slave = ANALOG_WDG
    write(line_a, slave, 0x014, 1000, 2000, 3000, 4000)  # analog outputs 0..3
    write(line_a, slave, 0x03E, 100, 200, 300, 400)  # fallback values
    write(line_a, slave, 0x046, 0x0005)  # outputs 0 and 2 may fall back
    write(line_a, slave, 0x03D, 0x0003)  # digital fallback: outputs 0 and 1 at 1
    write(line_a, slave, 0x013, 0x000C)
    write(line_a, slave, 0x03C, 10)  # 1 s of silence
    wait_sim(tcp, sim_ticks(tcp) / 10 + 2.0)  # 2 simulated s of silence to this TES
    first, second = words(line_a, slave, 0x000)[0], words(line_a, slave, 0x000)[0]
    assert first & 0x02 and not second & 0x03  # §6.4.1 reset at the first exchange
    write(line_a, slave, 0x03C, 0)
    assert words(line_a, slave, 0x014, 4) == [100, 2000, 300, 4000]  # §4.3.2 authorised only
    states = words(line_a, slave, 0x00B, 4)
    assert [s & 0x02 for s in states] == [2, 0, 2, 0]  # §6.4.4 bit 1
    assert words(line_a, slave, 0x013) == [0x0003]
    assert words(line_a, slave, 0x01C)[0] >> 8 == 0x3  # direct outputs
    write(line_a, slave, 0x014, 5000)  # the master commands output 0 again
    assert words(line_a, slave, 0x00B, 4)[0] & 0x02 == 0
