"""The cores' typed fault calls, and the names of each kind's table mapped onto them."""

from __future__ import annotations

import pytest

from fieldtwin.devices.aem811.faults import FAULTS as AEM_FAULTS
from fieldtwin.devices.dem24.status import details as dem_details
from fieldtwin.devices.faults import table_for
from fieldtwin.devices.scm.faults import FAULTS as SCM_FAULTS
from fieldtwin.errors import ConfigError
from fieldtwin.facade import fault_names, inject_fault
from fieldtwin.tes import Tes
from fieldtwin.tes.state import LineFault
from fieldtwin.tsx.aem811 import Aem811
from fieldtwin.tsx.dem24.models import Dem24
from fieldtwin.tsx.plc import Plc
from fieldtwin.tsx.scm.module import ScmModule


def _plc_with(type_name: str, slot: int = 3) -> tuple[Plc, object]:
    plc = Plc()
    module = plc.insert(type_name, slot=slot)
    plc.advance(3.0)
    return plc, module


def test_aem_typed_calls_and_their_names() -> None:
    plc, mod = _plc_with("TSX AEM 811")
    assert isinstance(mod, Aem811) and table_for(mod) is AEM_FAULTS
    mod.set_wire_break(3, True)
    assert mod.cut[3] and not mod.cut[2]
    inject_fault(mod, "open_3", False)
    assert not mod.cut[3]
    mod.set_terminal_block(False)
    plc.advance(0.05)
    assert plc.read("IW3,0,A") == 1 and plc.read("I3,S") == 1  # AEM 4.4-1: terminal block
    inject_fault(mod, "terminal_block", False)
    plc.advance(0.05)
    assert plc.read("IW3,0,A") == 0 and plc.read("I3,S") == 0
    with pytest.raises(ConfigError, match="not allowed"):
        mod.set_wire_break(8, True)
    with pytest.raises(ConfigError, match=r"unknown fault 'smoke' for TSX AEM 811 \(allowed: "):
        inject_fault(mod, "smoke", True)
    with pytest.raises(ConfigError, match="takes no parameters, not ms"):
        inject_fault(mod, "open_1", True, ms=3)


def test_dem_pulses_need_a_pulse_source() -> None:
    _, mod = _plc_with("TSX DEM 2412")
    assert isinstance(mod, Dem24)
    with pytest.raises(ConfigError, match="no pulse source"):
        mod.set_pulses_lost(True)
    assert set(fault_names(mod)) == {"terminal_block", "supply", "pulses"}
    assert dem_details(mod)["oscillating"] == "none"


def test_scm_typed_calls() -> None:
    _, mod = _plc_with("TSX SCM 2111")
    assert isinstance(mod, ScmModule) and table_for(mod) is SCM_FAULTS
    mod.set_parity_errors(1, True)
    assert mod.lines[1].inject_parity and not mod.lines[0].inject_parity
    inject_fault(mod, "format_ch0", True)
    assert mod.lines[0].inject_format
    with pytest.raises(ConfigError, match="does not exist"):
        mod.set_format_errors(2, True)
    with pytest.raises(ConfigError, match="self-test fault bit 5 not allowed"):
        mod.set_self_test_fault(5, True)


def test_tes_typed_calls_are_the_faults_in_force() -> None:
    tes = Tes("TES 8EA", slave=1)
    tes.set_no_answer(True)
    tes.set_late_answer(25)
    tes.set_corrupt_frames(LineFault.BAD_CRC, True, count=2)
    tes.set_not_ready(True, window_ms=2)
    assert tes.active_faults() == {
        "no_answer": {},
        "late_answer": {"ms": 25.0},
        "bad_crc": {"count": 2},
        "not_ready": {"window_ms": 2.0},
    }
    tes.set_late_answer(0)
    tes.set_no_answer(False)
    tes.set_corrupt_frames(LineFault.BAD_CRC, False)
    tes.set_not_ready(False)
    assert tes.active_faults() == {}
    with pytest.raises(ConfigError, match=r"allowed 0\.\.60000 ms"):
        tes.set_late_answer(60_001)
    with pytest.raises(ConfigError, match=r"allowed 0\.\.<100 ms"):
        tes.set_not_ready(True, window_ms=100)
    with pytest.raises(ConfigError, match="not served on a TCP endpoint"):
        tes.drop_connections()
    closed: list[int] = []
    tes.line_faults.droppers.append(lambda: closed.append(1) or 2)
    assert tes.drop_connections() == 2 and closed == [1]


def test_object_entries_are_typed() -> None:
    from fieldtwin.devices.face import ObjectEntry
    from fieldtwin.devices.module import ModuleDevice
    from fieldtwin.devices.tes import TesDevice
    from fieldtwin.modbus.model import Link

    plc, mod = _plc_with("TSX AEM 811", slot=5)
    assert isinstance(mod, Aem811)
    entries = ModuleDevice(mod, plc).objects().names()
    assert entries[0] == ObjectEntry("IW5,0") and entries[0].text == "IW5,0"
    assert entries[-1].address == "I5,S" and entries[-1].name == ""
    tes = TesDevice(Tes("TES 8EA", slave=1), "tcp://127.0.0.1:5020", Link.RS485, {}, "tes[0]")
    by_name = {e.name: e for e in tes.objects().names()}
    entry = by_name["analog_input[0]"]
    assert entry.address == "H'003'" and entry.text == "H'003' analog_input[0]"
    assert tes.objects().peek(entry.address) == tes.objects().peek(entry.name)


def test_addresses_are_open_and_say_their_ids() -> None:
    from fieldtwin.devices import registry
    from fieldtwin.devices.face import Address, Family, ModuleAddress, TesAddress

    module: Address = ModuleAddress(2, 3)
    assert module.text == "23" and module.selects(" 23 ") and not module.selects("3")
    first, second = TesAddress("tcp://a:1", 1), TesAddress("tcp://b:2", 1)
    peers: list[Address] = [module, first, second, TesAddress("tcp://b:2", 2)]
    assert [a.ident(peers) for a in peers] == ["23", "tes1", "tes1@2", "tes2"]
    assert first.selects("tcp://a:1   1") and first.key == ("tes", "tcp://a:1", 1)
    pump = Family("pump", "pump", "model", "pump model")  # a third family: a value, no edit
    assert pump != Family.MODULE and str(Family.TES) == "tes" and Family.MODULE.key == "type"
    assert registry.families()[:2] == [Family.MODULE, Family.TES]
    with pytest.raises(ConfigError, match="unknown pump model 'P1' \\(allowed: none installed\\)"):
        registry.kind_named("P1", pump)


def test_the_documented_fault_calls_on_a_core_still_work() -> None:
    """`tes.inject_fault(...)`, `tes.fault_names()` and `mod.inject_fault(name, on)` (the
    names docs/tes.md and docs/aem811.md gave) reach the same tables as the façade."""
    from fieldtwin.tes import Tes
    from fieldtwin.tsx.plc import Plc

    tes = Tes("8EA")
    assert "late_answer" in tes.fault_names()
    tes.inject_fault("late_answer", True, ms=20)
    assert tes.active_faults() == {"late_answer": {"ms": 20.0}}
    tes.inject_fault("late_answer", False)
    assert tes.active_faults() == {}
    plc = Plc(model="TSX 87", scan_ms=10)
    aem = plc.insert("TSX AEM 811", rack=0, slot=5, code=648)
    assert "open_3" in aem.fault_names()
    aem.inject_fault("open_3", True)
    aem.inject_fault("open_3", False)
