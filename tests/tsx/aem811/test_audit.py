"""Edge cases found in the second audit: faults, Stop/Run, hysteresis and timing boundaries."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.clock import MS
from fieldtwin.devices.aem811.plantkeys import read_plant_table
from fieldtwin.errors import ConfigError
from fieldtwin.facade import inject_fault
from fieldtwin.tsx.aem811.ranges import RANGES
from fieldtwin.tsx.aem811.scaling import ChannelConfig, Scaling, measure
from tests.tsx.aem811.helpers import CHN, SYS, at, configure, make, ready, run, until, words


def test_4_4_1_blocking_fault_ends_a_held_threshold_write() -> None:
    # AEM 4.4-1: a blocked module makes no exchange; the held request must end (TXTi,S = 4)
    plc, mod = ready()
    tb = plc.start_exchange(m=CHN, c=2, send=[5] * 8)  # held: module stopped
    plc.advance(0.1)
    assert not tb.done
    inject_fault(mod, "processor", True)
    plc.advance(0.05)
    assert tb.done and tb.result is not None
    assert (tb.result.e, tb.result.s) == (True, 4)
    assert mod.thresholds.values[0] == [0] * 8


def test_4_4_1_request_held_by_the_self_test_ends_at_a_blocking_fault() -> None:
    plc, mod = make()
    tb = plc.start_exchange(m=SYS, c=0x0F, recv_bytes=27)  # held until the self-test ends
    plc.advance(5)
    inject_fault(mod, "processor", True)
    plc.advance(0.05)
    assert tb.done and tb.result is not None and (tb.result.e, tb.result.s) == (True, 4)


def test_2_5_4_converter_fault_freezes_values_and_threshold_bits() -> None:
    # AEM 2.5-4 / 4.1-2: the module goes to Stop until the fault disappears; the
    # registers and the detection bits keep what they had, nothing is acquired
    plc, mod = ready(quantize=False)
    for ch in range(8):
        mod.set_input(ch, volts=5.0)
    run(plc, mod)
    plc.advance(1.1)
    assert plc.read("IW5,6") == 5000 and plc.read("I5,3") == 1
    inject_fault(mod, "converter", True)
    plc.advance(0.05)
    for ch in range(8):
        mod.set_input(ch, volts=-5.0)
    plc.advance(2)
    assert plc.read("IW5,0,C") == 0 and plc.read("I5,S") == 1
    assert plc.read("IW5,6") == 5000 and plc.read("I5,3") == 1
    tb = plc.start_exchange(m=CHN, c=2, send=[0] * 8)
    plc.advance(1)
    assert not tb.done  # AEM 4.3-1: acknowledged at Run, after the fault
    inject_fault(mod, "converter", False)
    plc.advance(1.2)
    assert tb.done and plc.read("IW5,0,C") == 1
    assert plc.read("IW5,6") == 0xFFFF & -5000 and plc.read("I5,3") == 0


def test_stop_mid_acquisition_loses_the_slot_and_run_restarts_at_channel_0() -> None:
    plc, mod = ready(quantize=False)
    mod.set_input(2, volts=2.0)
    t = run(plc, mod)
    until(plc, at(t, 250))  # channel 2 sampled at 200, due at 300
    plc.write("OW5,0,C", 0)
    plc.advance(0.02)
    until(plc, at(t, 400))
    assert mod.iw[5] == 0 and mod.relay_operations[2] == 1
    plc.write("OW5,0,C", 1)
    plc.advance(0.02)
    restart = mod.run_started_at_us
    assert restart is not None
    until(plc, at(restart, 299.999))
    assert mod.iw[5] == 0
    until(plc, at(restart, 300))  # the new cycle starts with channel 0
    assert mod.iw[5] == 2000 and mod.relay_operations[2] == 2


def test_4_1_4_plc_sees_the_value_the_instant_it_reaches_the_register() -> None:
    plc, mod = ready(quantize=False)
    mod.set_input(1, volts=1.5)
    t = run(plc, mod)  # Run at a PLC bus refresh: slots fall on task ends
    until(plc, at(t, 199.999))
    assert plc.read("IW5,4") == 0
    until(plc, at(t, 200))
    assert plc.read("IW5,4") == 1500 and plc.read("IW5,2,1") == 0


def test_4_1_4_accelerated_holding_time_is_n_x_100_ms() -> None:
    # n = 3 channels on three different registers: each updated every 300 ms
    plc, mod = ready(quantize=False)
    mod.set_input(0, volts=0.5)
    plc.write("OW5,1", 0x100 | 0xF8)  # accelerated, channels 0, 1, 2 enabled
    t = run(plc, mod)
    changes: list[tuple[int, int]] = []
    for step in range(1, 12):
        until(plc, at(t, 100 * step - 50))
        mod.set_input(0, volts=step)  # a new value every 100 ms
        until(plc, at(t, 100 * step))
        if not changes or mod.iw[3] != changes[-1][1]:
            changes.append((100 * step, mod.iw[3]))
    # channel 0 sampled at 0, 300, 600, 900 ms, each value in IWxy,3 100 ms later
    assert changes == [(100, 500), (400, 3000), (700, 6000), (1000, 9000)]
    assert mod.relay_operations[:4] == [4, 4, 4, 0]


def test_inhibit_mirror_and_forcing_while_stopped() -> None:
    plc, mod = ready(quantize=False)
    mod.set_input(6, volts=6.0)
    t = run(plc, mod)
    until(plc, at(t, 800))
    assert plc.read("I5,6") == 1 and plc.read("IW5,5") == 6000
    plc.write("OW5,0,C", 0)
    plc.write("OW5,1,6", 1)
    plc.advance(0.02)
    assert plc.read("IW5,0,C") == 0 and plc.read("IW5,1,6") == 1
    assert plc.read("I5,6") == 0 and plc.read("IW5,5") == 0  # ch 2: never acquired
    assert plc.exchange(m=CHN, c=1, recv_bytes=16).words[6] == 0


def test_2_3_5_standard_bipolar_boundaries_with_a_negative_threshold() -> None:
    # standard scaling: h = 50 for every range (AMB-AEM-12), so T +/- 25
    plc, mod = ready(quantize=False)
    configure(plc, [0x00C0, 0x00B0])  # -10/+10 V standard: -10000..10000
    run(plc, mod)
    plc.exchange(m=CHN, c=2, send=words([-5000] + [0] * 7))

    def bit_at(millivolts: float) -> int:
        mod.set_input(0, volts=millivolts / 1000)
        plc.advance(1.1)
        return plc.read("I5,0")

    assert [bit_at(mv) for mv in (-9000, -4976, -4975, -5024, -5025, -4976)] == [0, 0, 1, 1, 0, 0]


def test_2_3_2_square_root_below_zero() -> None:
    # AEM 2.3-2: -100 x sqrt(-m) for a negative standardized measurement
    std = ChannelConfig(2, True, Scaling.STANDARD)
    assert measure(-100, std, quantize=False).value == -1000  # -1.00 % -> -10.00 %
    m = measure(-200, std, quantize=False)
    assert (m.value, m.faulty) == (-1414, False)  # ELL: the zone's lower end
    m = measure(-300, std)
    assert (m.value, m.below) == (-1414, True)  # beyond ELL: clamped, ELL fault
    user = ChannelConfig(2, True, Scaling.USER, high=20000, low=0)
    assert measure(-100, user, quantize=False).value == -2000
    bipolar = ChannelConfig(0, True, Scaling.STANDARD)
    assert measure(-2500, bipolar, quantize=False).value == -5000
    assert measure(2500, bipolar, quantize=False).value == 5000


def test_2_3_4_open_input_reads_ehl_and_the_thresholds_see_it() -> None:
    # AEM 2.3-4: "the module nevertheless acquires ... EHL": the comparison is made
    # with it, so the program must check the channel fault bit (IWxy,1,8+i)
    plc, mod = ready(quantize=False)
    configure(plc, [0x00A0, 24, 0x00C0, 0x20A1])
    mod.set_input(0, volts=2.0)
    run(plc, mod)
    plc.exchange(m=CHN, c=4, send=[9000] + [0] * 7)
    plc.advance(2.5)
    assert plc.read("I5,8") == 0
    mod.set_input(0, open_circuit=True)
    plc.advance(2.5)
    assert plc.read("IW5,3") == RANGES[2].ehl and plc.read("I5,8") == 1
    assert plc.read("IW5,1,8") == 1 and mod.leds["ERR"] == "on"


def test_0_20_ma_open_line_is_a_zero_current() -> None:
    plc, mod = ready(quantize=False)
    configure(plc, [0x00C0, 0x70A0, 0x00C4, 0x80A0])
    mod.set_input(0, open_circuit=True)
    inject_fault(mod, "open_4", True)
    run(plc, mod)
    plc.advance(1.1)
    assert mod.values[0] == 0 and plc.read("IW5,1,8") == 0  # 0/20 mA: cannot tell
    assert mod.values[4] == 3680 and plc.read("IW5,1,C") == 1  # 4/20 mA: under range


def test_threshold_write_acknowledged_at_the_end_of_the_slot_in_progress() -> None:
    plc, mod = ready(quantize=False)
    t = run(plc, mod)
    until(plc, at(t, 930))  # normal mode: waiting for the next cycle at 1000 ms
    tb = plc.start_exchange(m=CHN, c=2, send=[1] * 8)
    until(plc, at(t, 1099.999))
    assert not tb.done and mod.pending_thresholds is not None
    until(plc, at(t, 1100))
    assert mod.pending_thresholds is None and mod.thresholds.values[0] == [1] * 8
    plc.advance(0.02)
    assert tb.done and tb.result is not None and tb.result.v == 0xFE
    assert plc.now - at(t, 1100) <= 20 * MS


@pytest.mark.parametrize(
    ("channel", "match"),
    [
        ({"channel": 0, "range": "0/10V", "scalling": "user"}, r"\.scalling: unknown key"),
        ({"channel": 0, "range": "0/10V", "sqrt": "no", "scaling": "B"}, "sqrt: 'no' is not"),
        ({"channel": 0, "range": "0/10V", "continuity": 1}, r"continuity: 1 is not true"),
        ({"channel": 0, "range": "0/10V", "high": 100, "low": 0}, "high: limits are only"),
        ({"channel": 0, "mode": "H'20B0'", "low": 0}, "low: limits are only for user"),
        ({"channel": 0, "mode": "H'20B0'", "range": 2}, "range: give either mode"),
    ],
)
def test_plant_channel_mistakes_are_named(
    channel: dict[str, object], match: str, tmp_path: Path
) -> None:
    plc, mod = make()
    with pytest.raises(ConfigError, match=match):
        read_plant_table(mod, {"config": {"channels": [channel]}}, "module[0]", tmp_path)


def test_plant_unknown_config_key_is_named(tmp_path: Path) -> None:
    plc, mod = make()
    with pytest.raises(ConfigError, match=r"config\.periode"):
        read_plant_table(mod, {"config": {"periode": 30}}, "module[0]", tmp_path)
