"""AEM 5.1: four tanks, level on channels 0..3 (4/20 mA), flow on 4..7 (0/10 V, sqrt).

Run end to end through Text Blocks and register reads, the way the §5.1 program
does it: stop, send CW0[34], run, send thresholds 0 and 1, then demultiplex
IW5,3..6 with IW5,2,0..3 into W0..W7 at each master-task cycle (§4.1-1).
"""

from __future__ import annotations

from fieldtwin.facade import inject_fault
from fieldtwin.signals import PiecewiseLinear
from fieldtwin.tsx.aem811 import Aem811
from fieldtwin.tsx.aem811.faults import describe
from fieldtwin.tsx.plc import Plc
from tests.tsx.aem811.helpers import (
    CHN,
    SYS,
    TANK_CONFIG,
    TANK_THRESHOLD_0,
    TANK_THRESHOLD_1,
    make,
    words,
)

S_US = 1_000_000


def level_ma(mm: float) -> float:
    return 4.0 + mm * 16.0 / 10000  # 4 mA -> 0 mm, 20 mA -> 10000 mm


def flow_volts(milli_l_min: float) -> float:
    return 10.0 * (milli_l_min / 20000) ** 2  # flow = 20000 x sqrt(V / 10 V)


def sr2(plc: Plc, table: list[int], seconds: float) -> None:
    """§4.1-1 / §5.1 SR2, scan by scan: valid measurements into W0..W7."""
    for _ in range(round(seconds / 0.01)):
        plc.advance(0.01)
        if not plc.read("IW5,0,C") or plc.read("I5,S"):
            continue
        selector, faults = plc.read("IW5,2"), plc.read("IW5,1") >> 8
        for index in range(4):
            channel = index + 4 * (selector >> index & 1)
            if not faults >> channel & 1:
                value = plc.read(f"IW5,{3 + index}")
                table[channel] = value - 0x10000 if value & 0x8000 else value


def set_up() -> tuple[Plc, Aem811, list[int]]:
    plc, mod = make(code=648)
    # tank 0 fills from 500 mm to 8500 mm in 60 s, then drains back
    points = [(0, level_ma(500)), (70 * S_US, level_ma(500)), (130 * S_US, level_ma(8500))]
    points += [(190 * S_US, level_ma(500))]
    mod.set_signal(0, PiecewiseLinear(points), unit="mA")
    for ch in (1, 2, 3):
        mod.set_input(ch, milliamps=level_ma(5000))
    mod.set_input(4, volts=flow_volts(10000))
    for ch in (5, 6, 7):
        mod.set_input(ch, volts=flow_volts(16000))
    # main program: wait for the self-test (IW5,0,3), stop, configure (SR0)
    plc.advance(10.05)
    assert plc.read("IW5,0,3") == 1 and plc.read("IW5,2,D") == 1
    plc.write("OW5,0", 0)
    plc.write("OW5,1", 0)
    plc.advance(0.02)
    r = plc.exchange(m=SYS, c=0x40, send=words(TANK_CONFIG))
    assert (r.v, r.e, len(TANK_CONFIG) * 2) == (0xFE, False, 68)
    plc.advance(0.02)
    assert plc.read("IW5,0,B") == 0 and plc.read("IW5,2,D") == 0
    # SR1: run the module, then thresholds 0 and 1 (acknowledged once compared)
    plc.write("OW5,0,C", 1)
    plc.advance(0.02)
    assert plc.exchange(m=CHN, c=2, send=words(TANK_THRESHOLD_0)).v == 0xFE
    assert plc.exchange(m=CHN, c=4, send=words(TANK_THRESHOLD_1)).v == 0xFE
    r = plc.exchange(m=CHN, c=3, recv_bytes=16)
    assert (r.v, r.words) == (0x83, TANK_THRESHOLD_0)
    table = [0] * 8
    sr2(plc, table, 6.0)
    return plc, mod, table


def near(value: int, expected: int, tolerance: int = 3) -> bool:
    return abs(value - expected) <= tolerance


def test_5_1_levels_flows_and_thresholds() -> None:
    plc, mod, w = set_up()
    assert near(w[0], 500) and all(near(w[ch], 5000) for ch in (1, 2, 3))
    assert near(w[4], 10000) and all(near(w[ch], 16000) for ch in (5, 6, 7))
    # low level tank 0 (threshold 0 = 1000 not reached), high level not reached
    assert (plc.read("I5,0"), plc.read("I5,8")) == (0, 0)
    assert [plc.read(f"I5,{ch}") for ch in (1, 2, 3)] == [1, 1, 1]
    # flow alarm (threshold 0 = 15000) on tanks 1..3, not on tank 0
    assert [plc.read(f"I5,{ch}") for ch in (4, 5, 6, 7)] == [0, 1, 1, 1]
    r = plc.exchange(m=CHN, c=1, recv_bytes=16)  # §4.2 message mode agrees
    assert r.v == 0x81 and all(near(a, b) for a, b in zip(words(w), r.words, strict=True))


def test_5_1_threshold_bits_switch_with_hysteresis() -> None:
    plc, mod, w = set_up()
    # tank 0 fills then drains: I5,0 / I5,8 switch at threshold +/- h/2 (h = 52)
    changes: list[tuple[str, int, int]] = []
    state = {name: plc.read(name) for name in ("I5,0", "I5,8")}
    while plc.now < 200 * S_US:
        sr2(plc, w, 1.0)
        for name, old in state.items():
            new = plc.read(name)
            if new != old:
                changes.append((name, new, w[0]))
                state[name] = new
    assert [(n, v) for n, v, _ in changes] == [("I5,0", 1), ("I5,8", 1), ("I5,8", 0), ("I5,0", 0)]
    levels = {(n, v): level for n, v, level in changes}
    assert 1026 <= levels["I5,0", 1] <= 1026 + 420  # a 3 s cycle: 400 mm at most
    assert 8026 <= levels["I5,8", 1] <= 8026 + 420
    assert 7974 - 420 <= levels["I5,8", 0] <= 7974
    assert 974 - 420 <= levels["I5,0", 0] <= 974
    # a flow hovering inside the band keeps its bit
    mod.set_input(5, volts=flow_volts(14990))
    sr2(plc, w, 6.0)
    assert near(w[5], 14990) and plc.read("I5,5") == 1
    mod.set_input(5, volts=flow_volts(14900))
    sr2(plc, w, 6.0)
    assert plc.read("I5,5") == 0


def test_5_1_sensor_faults_through_the_fault_bit_string() -> None:
    plc, mod, w = set_up()
    inject_fault(mod, "open_2", True)  # level transducer line cut: under 4 mA
    mod.set_input(6, open_circuit=True)  # flow transducer disconnected
    sr2(plc, w, 3.2)
    assert plc.read("IW5,1,A") == 1 and plc.read("IW5,1,E") == 1  # SR3: sensor faults
    assert plc.read("IW5,0,4") == 1 and plc.read("IW5,0,7") == 1 and plc.read("I5,S") == 0
    assert mod.leds["ERR"] == "on" and mod.values[2] == -200 and mod.values[6] == 20976
    assert near(w[2], 5000) and near(w[6], 16000)  # SR2 keeps the last valid values
    r = plc.exchange(m=SYS, c=0x47, recv_bytes=8)  # SR3: 8 -> W25
    assert r.v == 0x77
    assert describe(r.data) == ["channel 2 ELL exceeded", "channel 6 continuity"]
    inject_fault(mod, "open_2", False)
    mod.set_input(6, volts=flow_volts(16000))
    sr2(plc, w, 3.2)
    assert plc.read("IW5,1") == 0 and plc.read("IW5,0,7") == 0 and mod.leds["ERR"] == "off"
