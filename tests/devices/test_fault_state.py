"""Issue 21 item 1: the face tells which faults are in force, which apply, and every output.

In-process on simulated time: the control API's resources (what the routes
call), the console, the live view and the plant file see the same fault state
through the Device face; a TES line fault no port of the TES carries is refused,
naming the port kinds where it applies; a TES 4SA's analog output reads in volts
with the word the master wrote beside.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from fieldtwin.console import Console
from fieldtwin.control.resources import Control, NotFound
from fieldtwin.devices.face import FaultNotApplicable
from fieldtwin.errors import ConfigError
from fieldtwin.live import plain_status
from fieldtwin.plant import Plant, load_plant
from fieldtwin.runtime.runner import Runner

PLANT = """
[plc]
model = "TSX 87"

[[module]]
type = "TSX AEM 811"
slot = 5

[[module]]
type = "TSX DST 1635"
slot = 6

[[tes]]
model = "TES 32EST"
endpoint = "tcp://127.0.0.1:0"
slave = 1

[[tes]]
model = "TES 4SA"
endpoint = "pty"
slave = 2
"""


@pytest.fixture
def plant(tmp_path: Path) -> Iterator[Plant]:
    path = tmp_path / "plant.toml"
    path.write_text(PLANT)
    loaded = load_plant(path)
    yield loaded
    loaded.close()


@pytest.fixture
def control(plant: Plant) -> Control:
    return Control(plant, Runner(plant.clock, None), plant.events)


def _fault(control: Control, device: str, name: str) -> dict[str, object]:
    return next(f for f in control.faults(device) if f["name"] == name)


def test_each_fault_says_whether_it_is_in_force_and_with_which_parameters(
    control: Control,
) -> None:
    late = _fault(control, "tes1", "late_answer")
    assert late["active"] is False and late["params"] == {}
    assert late["takes"] == ["ms"] and late["hint"] == "ms=200"
    assert _fault(control, "tes1", "not_ready")["hint"] == "count=3 window_ms=20"
    control.set_fault("tes1", "late_answer", True, {"ms": 200})
    late = _fault(control, "tes1", "late_answer")
    assert late["active"] is True and late["params"] == {"ms": 200}
    status = control.status("tes1")
    assert status["active_faults"] == {"late_answer": {"ms": 200}}
    control.set_fault("tes1", "late_answer", False, {})
    assert control.status("tes1")["active_faults"] == {}
    # a module's fault: what was set through the face, until it is cleared
    control.set_fault("5", "terminal_block", True, {})
    assert _fault(control, "5", "terminal_block")["active"] is True
    assert control.status("5")["active_faults"] == {"terminal_block": {}}
    control.set_fault("5", "terminal_block", False, {})
    assert _fault(control, "5", "terminal_block")["active"] is False


def test_the_console_marks_the_faults_in_force(control: Control, plant: Plant) -> None:
    console = Console(plant)
    console.execute("tes 1 fault late_answer on ms=250")
    lines = console.execute("tes 1 faults")
    assert "* late_answer active ms=250" in lines
    assert not any(line.startswith("* ") and "no_answer" in line for line in lines)
    console.execute("fault 5 open_3 on")
    assert "* open_3 active" in console.execute("faults 5")
    assert "faults: open_3" in console.execute("status 5")
    assert any("faults: late_answer ms=250" in line for line in plain_status(plant))
    assert any("slot 5 " in line and "faults: open_3" in line for line in plain_status(plant))


def test_a_line_fault_no_port_carries_is_refused_naming_the_port_kinds(
    control: Control, plant: Plant
) -> None:
    names = [f["name"] for f in control.faults("tes1")]
    assert "bad_crc" not in names and "broken_character" not in names  # Modbus TCP
    assert "drop_connections" in names
    with pytest.raises(FaultNotApplicable, match=r"'bad_crc'.*RTU over TCP or RTU line"):
        control.set_fault("tes1", "bad_crc", True, {})
    with pytest.raises(FaultNotApplicable, match=r"this device has Modbus TCP"):
        Console(plant).execute("tes 1 fault broken_character on")
    rtu = [f["name"] for f in control.faults("tes2")]
    assert "bad_crc" in rtu and "drop_connections" not in rtu  # an RTU line (pty)
    with pytest.raises(FaultNotApplicable, match=r"'drop_connections'.*Modbus TCP or RTU over"):
        control.set_fault("tes2", "drop_connections", True, {})
    with pytest.raises(NotFound, match="unknown fault 'smoke'"):
        control.set_fault("tes2", "smoke", True, {})


def test_the_plant_file_refuses_a_line_fault_the_port_does_not_carry(tmp_path: Path) -> None:
    path = tmp_path / "plant.toml"
    path.write_text(
        '[[tes]]\nmodel = "TES 8EA"\nendpoint = "tcp://127.0.0.1:0"\nslave = 1\n'
        'faults = ["bad_crc"]\n'
    )
    with pytest.raises(ConfigError, match=r"tes\[0\]\.faults: fault 'bad_crc' does not apply.*RTU"):
        load_plant(path)


def test_a_tes_4sa_analog_output_in_volts_with_the_word_beside(
    control: Control, plant: Plant
) -> None:
    tes = plant.tes_device(2, None)
    control.write_object("tes2", "H'014'", 0x4000)
    volts = tes.tes.analog_output(0)
    assert 0 < volts <= 10
    outputs = {o["name"]: o for o in control.outputs("tes2")}
    assert list(outputs)[:4] == ["0", "1", "2", "3"]  # the digital outputs first
    a0 = outputs["a0"]
    assert a0["unit"] == "V" and a0["raw"] == 0x4000
    assert a0["value"] == pytest.approx(volts, abs=1e-4)
    assert a0["description"] == "analog, V"
    status = control.status("tes2")
    assert {"name": "a0", "value": a0["value"], "unit": "V", "raw": 0x4000} == {
        k: v for k, v in status["outputs"][4].items() if k != "text"
    }
    lines = Console(plant).execute("tes 2 outputs")
    assert f"a0 = {volts:.3f}V (H'4000')" in lines


def test_an_output_module_lists_its_bits(control: Control, plant: Plant) -> None:
    assert plant.plc is not None
    plant.plc.advance(1.0)  # the module's self-test done
    plant.plc.write("O6,3", 1)
    plant.plc.advance(0.1)  # the PLC's output exchange
    outputs = {o["name"]: o["value"] for o in control.outputs("6")}
    assert len(outputs) == 16 and outputs["3"] is True and outputs["2"] is False
    assert control.outputs("5") == []  # the AEM drives no output
    assert "3 = 1" in Console(plant).execute("outputs 6")
