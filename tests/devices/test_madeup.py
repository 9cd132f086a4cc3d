"""A made-up device added through the registry alone, driven from a plant file and the console."""

from __future__ import annotations

from pathlib import Path

import pytest

import tests.devices.madeup  # noqa: F401  its registry line
from fieldtwin.console import Console
from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from tests.devices.madeup import LEVEL

PLANT = f"""
[plc]
model = "TSX 87"

[[module]]
type = "{LEVEL}"
slot = 3
inputs = {{ "0" = {{ kind = "ramp", start = 0.0, end = 10.0, t0_s = 1, duration_s = 10 }} }}
faults = ["float_stuck"]
"""


def test_a_made_up_device_from_the_plant_file_and_the_console(tmp_path: Path) -> None:
    path = tmp_path / "plant.toml"
    path.write_text(PLANT)
    console = Console(load_plant(path))
    console.execute("advance 6")  # 1 s self-test, then the ramp: 5 V at t = 6 s
    assert console.execute("IW3,1") == ["IW3,1 = H'1388'"]  # 5000 mV
    assert console.execute("IW3,0,7") == ["IW3,0,7 = 1"]  # the fault from the plant file
    assert console.execute("faults 3") == ["float_stuck: the float switch is stuck"]
    assert console.execute("fault 3 float_stuck off") == ["fault 3 float_stuck off"]
    assert console.execute("input 3 0 2.5V") == ["input 3 0 = 2.5V"]
    console.execute("advance 200ms")
    assert console.execute("IW3,1") == ["IW3,1 = H'09C4'"]  # 2500 mV
    assert console.execute("signal 3 0 sine offset=4 amplitude=0 period_s=1") == [
        "signal 3 0 = sine"
    ]
    console.execute("advance 200ms")
    assert console.execute("IW3,1") == ["IW3,1 = H'0FA0'"]  # 4000 mV
    assert console.execute("leds 3") == ["OK=on ERR=off F=off"]
    status = console.execute("status 3")
    assert f"module: {LEVEL} rack 0 slot 3" in status
    with pytest.raises(ConfigError, match=r"TSX LVL 8 3: no input '1' \(allowed: 0\)"):
        console.execute("input 3 1 2V")


def test_its_plant_schema_is_checked_like_any_other(tmp_path: Path) -> None:
    path = tmp_path / "plant.toml"
    path.write_text(PLANT + "colour = 'red'\n")
    with pytest.raises(ConfigError, match=r"module\[0\]\.colour is not a key of TSX LVL 8"):
        load_plant(path)
