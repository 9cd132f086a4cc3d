"""AEM 5.1 end to end: the manual's four-tank program run by the twin PLC (issue 13)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.tsx.aem811 import Aem811
from fieldtwin.tsx.discrete import DiscreteInputs
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.plcmemory import TxtDeclaration
from tests.tsx.aem811.helpers import TANK_CONFIG, TANK_THRESHOLD_0, TANK_THRESHOLD_1

ROOT = Path(__file__).resolve().parents[3]
TANK = ROOT / "examples" / "aem811_tank.pl7"


def tank_plc() -> tuple[Plc, Aem811, DiscreteInputs]:
    plc = Plc("TSX 87")
    mod = plc.insert("TSX AEM 811", 0, 5, code=648)
    assert isinstance(mod, Aem811)
    det = plc.insert("TSX DET 805", 1, 4)
    assert isinstance(det, DiscreteInputs)
    plc.insert("TSX DST 1635", 1, 6)
    plc.insert("TSX DST 1635", 1, 7)
    plc.cw[0:34] = TANK_CONFIG
    plc.cw[100:108] = TANK_THRESHOLD_0
    plc.cw[108:116] = TANK_THRESHOLD_1
    plc.declare_text_block(0, TxtDeclaration(indirect=20))
    det.set_input(0, True)  # I14,0: Run
    for ch in range(4):
        mod.set_input(ch, milliamps=4.0 + 16.0 * 5000 / 10000)  # 5000 mm
    for ch in range(4, 8):
        mod.set_input(ch, volts=6.4)  # 16000 l/min
    plc.load_program(TANK)
    return plc, mod, det


def test_the_program_configures_writes_thresholds_and_copies_the_measurements() -> None:
    plc, mod, _ = tank_plc()
    plc.advance(9.9)  # the initial self-test: nothing sent yet
    assert plc.read("IW5,0,C") == 0 and plc.read("B3") == 0
    plc.advance(2.1)
    # SR0 sent CW0[34] (IW5,2,D = 0: configured), SR1 ran the module and wrote both
    # thresholds (B3: measurements processed from now on)
    assert plc.read("IW5,2,D") == 0 and plc.read("IW5,0,C") == 1 and plc.read("B3") == 1
    assert mod.thresholds.values == [TANK_THRESHOLD_0, TANK_THRESHOLD_1]
    assert plc.text_block(0).result is not None and plc.text_block(0).result.v == 0xFE
    levels = [plc.read(f"W{i}") for i in range(4)]
    flows = [plc.read(f"W{i}") for i in range(4, 8)]
    assert all(abs(v - 5000) <= 3 for v in levels), levels
    assert all(abs(v - 16000) <= 20 for v in flows), flows
    # threshold bits to the outputs: levels over threshold 0 (1000), under 1 (8000)
    i_bits = plc.image(0, 5).i_bits
    assert [plc.read(f"O16,{k:X}") for k in range(4)] == [(i_bits >> k) & 1 for k in range(4)]
    assert [plc.read(f"O16,{k:X}") for k in range(12, 16)] == [(i_bits >> k) & 1 for k in range(4)]
    assert [plc.read(f"O16,{k:X}") for k in range(4)] == [1, 1, 1, 1]
    assert [plc.read(f"O17,{k:X}") for k in range(4)] == [(i_bits >> k) & 1 for k in range(4, 8)]
    assert plc.read("O17,F") == 0 and plc.read("B4") == 0


def test_the_fault_processing_reacts_to_a_broken_input() -> None:
    plc, mod, _ = tank_plc()
    plc.advance(12.0)
    before = plc.read("W6")
    mod.set_input(6, open_circuit=True)  # tank 2's flow transducer disconnected
    plc.advance(2.0)
    # SR3: IW5,1 bit E (channel 6) -> O17,A; B4 set; W6 no longer copied
    assert plc.read("IW5,1,E") == 1
    assert plc.read("O17,A") == 1 and plc.read("B4") == 1
    assert [plc.read(f"O17,{k:X}") for k in range(4, 12) if k != 10] == [0] * 7
    assert plc.read("W6") == before
    mod.set_input(6, volts=6.4)
    plc.advance(3.0)
    assert plc.read("IW5,1,E") == 0 and plc.read("O17,A") == 0


def test_run_stop_switch_stops_the_module() -> None:
    plc, _, det = tank_plc()
    plc.advance(12.0)
    det.set_input(0, False)  # L6: NOT I14,0 . B3 -> RESET OW5,0,C
    plc.advance(0.1)
    assert plc.read("OW5,0,C") == 0
    plc.advance(0.1)
    assert plc.read("IW5,0,C") == 0


def test_a_plc_without_the_modules_the_program_names_refuses_it() -> None:
    plc = Plc("TSX 87")
    plc.insert("TSX AEM 811", 0, 5)
    with pytest.raises(ConfigError, match="no module in rack 1 slot 4"):
        plc.load_program(TANK)


def test_after_a_power_break_the_program_configures_the_module_again() -> None:
    plc, mod, _ = tank_plc()
    plc.advance(12.0)
    assert plc.read("IW5,2,D") == 0 and plc.read("B3") == 1
    plc.power_break(1.0)  # beyond the reserve: the AEM lost its configuration (2.5-3)
    plc.advance(0.5)
    assert plc.read("IW5,2,D") == 1  # the default configuration, until the program acts
    plc.advance(12.0)  # the self-test, then SR0 and SR1 again on IW5,2,D
    assert plc.read("IW5,2,D") == 0 and plc.read("IW5,0,C") == 1
    assert mod.thresholds.values == [TANK_THRESHOLD_0, TANK_THRESHOLD_1]
