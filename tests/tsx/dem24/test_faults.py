"""Terminal block and external supply faults (DEM 2.5-6, 3.2-1 DEF, 4.3), inputs (7.2)."""

from __future__ import annotations

import pytest

from fieldtwin.devices.dem24.plantkeys import console_value
from fieldtwin.errors import ConfigError
from fieldtwin.facade import inject_fault
from tests.tsx.dem24.helpers import M_SYS, SLOT, configure, make, read_all, synced


def test_4_3_terminal_block_removed_and_back() -> None:
    plc, mod = synced()
    mod.set_input(2, True)
    plc.advance(0.02)
    read_all(plc)
    inject_fault(mod, "terminal_block", True)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},0,A") == 1 and plc.read(f"IW{SLOT},0,6") == 1
    assert plc.read(f"IW{SLOT},0,4") == 1 and plc.read(f"I{SLOT},S") == 1
    assert plc.read(f"IW{SLOT},0,C") == 0  # 2.5-6: STOP until the fault disappears
    assert mod.leds == {"OK": "off", "ERR": "off", "F": "off"}
    assert plc.read(f"IW{SLOT},6") == 0  # DEF = 0: inputs forced to 0
    mod.set_input(5, True)  # not read while the terminal block is out
    plc.advance(0.02)
    inject_fault(mod, "terminal_block", False)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},0,A") == 0 and plc.read(f"IW{SLOT},0,C") == 1
    assert plc.read(f"IW{SLOT},0,6") == 1  # memorised until the fault string is read
    fault = plc.exchange(m=M_SYS, c=0x47, recv_bytes=12)
    assert fault.data[2] == 0x01  # bit 16
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},0,6") == 0
    assert plc.read(f"IW{SLOT},6") == (1 << 2) | (1 << 5)
    msgs = read_all(plc)
    assert [m[7] for m in msgs] == [(25 << 8) | 1, (25 << 8) | 0, (5 << 8) | 1]


def test_3_2_1_def_maintain_keeps_the_inputs() -> None:
    plc, mod = synced(config=[0x0040, 0, 0, 0, 0, 0, 60, 2, 0])
    mod.set_input(2, True)
    plc.advance(0.02)
    inject_fault(mod, "terminal_block", True)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},6") == 1 << 2


def test_external_supply_without_monitoring_drops_the_inputs() -> None:
    plc, mod = synced()
    mod.set_input(1, True)
    plc.advance(0.02)
    read_all(plc)
    inject_fault(mod, "supply", True)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},2,8") == 0 and plc.read(f"IW{SLOT},0,C") == 1
    assert plc.read(f"IW{SLOT},6") == 0
    assert [m[7] for m in read_all(plc)] == [(1 << 8) | 0]


def test_2_5_6_monitored_external_supply_fault() -> None:
    plc, mod = synced(config=[0x0001, 0, 0, 0, 0, 0, 60, 2, 0])
    mod.set_input(1, True)
    plc.advance(0.02)
    read_all(plc)
    inject_fault(mod, "supply", True)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},2,8") == 1 and plc.read(f"IW{SLOT},0,C") == 0
    assert plc.read(f"I{SLOT},S") == 1 and mod.leds["OK"] == "off"
    inject_fault(mod, "supply", False)
    plc.advance(0.03)
    assert plc.read(f"IW{SLOT},2,8") == 0 and plc.read(f"IW{SLOT},0,C") == 1
    assert [m[7] for m in read_all(plc)] == [(26 << 8) | 1, (26 << 8) | 0]


def test_terminal_block_missing_at_power_up() -> None:
    plc, mod = make()
    mod.set_terminal_block(False)
    plc.power_break(1.0)
    plc.advance(10.1)
    assert plc.read(f"IW{SLOT},0,A") == 1 and plc.read(f"IW{SLOT},0,C") == 0


def test_2_5_3_power_break_loses_configuration_time_and_messages() -> None:
    plc, mod = synced(config=[0x0010, 10, 0, 0, 0, 0, 60, 2, 5])
    mod.set_input(0, True)
    plc.advance(0.05)
    plc.power_break(1.0)
    plc.advance(10.1)
    assert plc.read(f"IW{SLOT},2,D") == 1 and plc.read(f"I{SLOT},0") == 0
    assert plc.read(f"IW{SLOT},5") == 0 and plc.read(f"IW{SLOT},6,0") == 1


def test_7_2_type_1_voltage_thresholds() -> None:
    plc, mod = make()
    for volts, level in [(4.9, 0), (15.0, 1), (10.0, 1), (5.0, 0), (10.0, 0), (24.0, 1)]:
        mod.set_input(0, volts)
        plc.advance(0.012)
        assert plc.read(f"IW{SLOT},6,0") == level, volts
    plc48, mod48 = make("TSX DEM 2413")
    mod48.set_input(0, 24.0)  # transition zone of the 48 V type 1
    plc48.advance(0.012)
    assert plc48.read(f"IW{SLOT},6,0") == 0
    mod48.set_input(0, 34.0)
    plc48.advance(0.012)
    assert plc48.read(f"IW{SLOT},6,0") == 1
    with pytest.raises(ConfigError):
        mod.set_input(24, True)
    mod.set_input(3, console_value("18.5V"))
    mod.set_input(4, console_value("on"))
    plc.advance(0.012)
    assert plc.read(f"IW{SLOT},6") & 0x18 == 0x18
    with pytest.raises(ConfigError):
        mod.set_input(4, console_value("maybe"))


def test_2_1_1_filters_reject_short_pulses() -> None:
    plc, mod = make()
    mod.set_input(0, True)
    plc.advance(0.0004)
    mod.set_input(0, False)  # 400 us: below the 500 us hardware filter
    plc.advance(0.01)
    assert plc.read(f"IW{SLOT},6,0") == 0 and mod.edges_stamped == 0
    configure(plc, [0, 20, 0, 0, 0, 0, 60, 2, 0])  # FILT = 20 ms
    mod.set_input(0, True)
    plc.advance(0.015)
    mod.set_input(0, False)
    plc.advance(0.05)
    assert mod.edges_stamped == 0
    mod.set_input(0, True)
    plc.advance(0.019)
    assert mod.inputs.level(0) is False
    plc.advance(0.002)
    assert mod.inputs.level(0) is True
