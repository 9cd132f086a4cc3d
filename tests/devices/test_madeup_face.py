"""The made-up device's output, fault with parameters, port of its own kind and stream
reach the control API, the console and the live view with no edit outside its file."""

from __future__ import annotations

from pathlib import Path

import pytest
from rich.console import Console as RichConsole

import tests.devices.madeup  # noqa: F401  its registry line
from fieldtwin.console import Console
from fieldtwin.control.panels import panels
from fieldtwin.control.resources import Control
from fieldtwin.devices.face import FaultNotApplicable
from fieldtwin.errors import ConfigError
from fieldtwin.live import plain_status, render
from fieldtwin.plant import Plant, load_plant
from fieldtwin.runtime.runner import Runner
from tests.devices.madeup import LEVEL


def _plant(tmp_path: Path, loop: bool) -> Plant:
    path = tmp_path / "plant.toml"
    path.write_text(
        f'[plc]\nmodel = "TSX 87"\n\n[[module]]\ntype = "{LEVEL}"\nslot = 3\n'
        'inputs = { "0" = 2.0 }\n' + ('loop = "4-20"\n' if loop else "")
    )
    return load_plant(path)


def test_its_line_fault_is_offered_only_where_its_loop_is(tmp_path: Path) -> None:
    plant = _plant(tmp_path, loop=False)
    control = Control(plant, Runner(plant.clock, None), plant.events)
    assert [f["name"] for f in control.faults("3")] == ["float_stuck"]
    with pytest.raises(FaultNotApplicable, match="ports of kind level loop; this device has no"):
        control.set_fault("3", "noise", True, {"mv": 50})
    plant.close()


def test_output_fault_port_and_stream_in_the_api_console_and_live_view(tmp_path: Path) -> None:
    plant = _plant(tmp_path, loop=True)
    assert plant.plc is not None
    control = Control(plant, Runner(plant.clock, None), plant.events)
    events = plant.events.subscribe(kinds=["level"])
    console = Console(plant)
    console.execute("advance 1.5")
    assert console.execute("IW3,1") == ["IW3,1 = H'07D0'"]  # 2000 mV
    # the fault with a parameter, from the API; its state everywhere
    noise = next(f for f in control.faults("3") if f["name"] == "noise")
    assert noise["active"] is False and noise["hint"] == "mv=1"
    control.set_fault("3", "noise", True, {"mv": 50})
    console.execute("advance 200ms")
    assert console.execute("IW3,1") == ["IW3,1 = H'0802'"]  # 2050 mV
    assert control.status("3")["active_faults"] == {"noise": {"mv": 50}}
    assert "* noise active mv=50" in console.execute("faults 3")
    assert any("faults: noise mv=50" in line for line in plain_status(plant))
    wide = RichConsole(width=160, record=True)
    wide.print(render(plant, []))
    assert "⚠ noise" in wide.export_text()
    with pytest.raises(ConfigError, match=r"mv = 5000 not allowed \(allowed 1..1000\)"):
        console.execute("fault 3 noise on mv=5000")
    # the output the program drives, in volts with the word beside
    plant.plc.write("OW3,0", 4500)
    console.execute("advance 100ms")
    assert control.outputs("3") == [
        {
            "name": "0",
            "description": "analog, V (the valve)",
            "value": 4.5,
            "unit": "V",
            "raw": 4500,
            "text": "4.500V (H'1194')",
        }
    ]
    assert console.execute("outputs 3") == ["0 = 4.500V (H'1194')"]
    assert "outputs: 0=4.500V (H'1194')" in console.execute("status 3")
    module = next(m for m in panels(control)["modules"] if m["id"] == "3")
    assert module["outputs"][0]["value"] == 4.5 and module["active_faults"] == ["noise mv=50"]
    # its port, of its own kind, in the status; its stream on the event bus
    assert control.device("3").ports()[0].kind.name == "level loop"
    samples = [e.data["mv"] for e in events.take() if e.device == "3"]
    assert samples and samples[-1] == 2050
    events.close()
    plant.close()
