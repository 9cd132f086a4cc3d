"""Issue 21 item 2: one value language; every analog TES takes volts and milliamps.

The plant file, the console and the Device face (which the control API calls)
all read ``"3V"``, ``"2500mV"``, ``"12mA"`` through fieldtwin.units; a bare
number keeps its meaning (volts, docs/tes.md "Units").  §4.3.1 gives the TES
converter's two spans, 0..10 V and 0..20 mA, both 0..1023 points (§4.2.4).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.console import Console
from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from fieldtwin.tes import Tes
from fieldtwin.units import Quantity

ANALOG_INPUT_MODELS = ("TES 4EA", "TES 8EA", "TES 8ESA")


def _plant(tmp_path: Path, inputs: str) -> Path:
    """The three analog-input models on one pty line (slaves 1, 2, 3), nothing opened."""
    path = tmp_path / "plant.toml"
    path.write_text(
        "".join(
            f'[[tes]]\nmodel = "{model}"\nendpoint = "pty"\nslave = {i + 1}\ninputs = {inputs}\n\n'
            for i, model in enumerate(ANALOG_INPUT_MODELS)
        )
    )
    return path


def test_the_plant_file_takes_volts_millivolts_and_milliamps_on_every_analog_tes(
    tmp_path: Path,
) -> None:
    path = _plant(tmp_path, '{ a0 = "2.0V", a1 = "12mA", a2 = "2500mV", a3 = 5.0 }')
    plant = load_plant(path)
    for tes in plant.tes:
        tes.advance(1.0)
        # 2 V of 10 V, 12 mA of 20 mA, 2.5 V, a bare 5 (volts)
        assert [tes.peek(0x003 + k) for k in range(4)] == [205, 614, 256, 512], tes.model.name


@pytest.mark.parametrize("n", [1, 2, 3])
def test_the_console_takes_volts_and_milliamps_on_every_analog_tes(tmp_path: Path, n: int) -> None:
    plant = load_plant(_plant(tmp_path, "{}"))
    console = Console(plant)
    assert console.execute(f"tes {n} input a1 3V") == [f"tes {n} input a1 = 3V"]
    assert console.execute(f"tes {n} input a2 12mA") == [f"tes {n} input a2 = 12mA"]
    assert console.execute(f"tes {n} input a3 4.5") == [f"tes {n} input a3 = 4.5"]
    tes = plant.tes[n - 1]
    tes.advance(1.0)
    assert [tes.peek(0x003 + k) for k in (1, 2, 3)] == [307, 614, 460]


@pytest.mark.parametrize("model", ANALOG_INPUT_MODELS)
def test_the_device_face_takes_the_units_the_api_sends(tmp_path: Path, model: str) -> None:
    plant = load_plant(_plant(tmp_path, "{}"))
    device = plant.tes_devices[ANALOG_INPUT_MODELS.index(model)]
    device.input("a1").set("3V")
    device.input("a0").set("12mA")
    device.tes.advance(1.0)
    assert [device.tes.peek(0x003), device.tes.peek(0x004)] == [614, 307]


@pytest.mark.parametrize("token", ["3 volts", "3A", "12mAh", "abc"])
def test_a_value_in_no_unit_of_the_input_names_the_token_and_the_units(
    tmp_path: Path, token: str
) -> None:
    plant = load_plant(_plant(tmp_path, "{}"))
    with pytest.raises(ConfigError, match=r"TES 4EA.* input a1: .*allowed"):
        plant.tes_devices[0].input("a1").set(token)


def test_a_duration_is_no_value_of_an_analog_input(tmp_path: Path) -> None:
    plant = load_plant(_plant(tmp_path, "{}"))
    with pytest.raises(ConfigError, match=r"input a1: 250ms is in s, not allowed here"):
        plant.tes_devices[0].input("a1").set("250ms")


def test_beyond_the_span_in_milliamps_saturates_with_the_note(tmp_path: Path) -> None:
    plant = load_plant(_plant(tmp_path, "{}"))
    note = plant.tes_devices[1].input("a0").set("25mA")
    assert note is not None and "saturated, it reads as 1023 points (§4.2.4)" in note


def test_the_plant_file_names_the_field_of_a_bad_unit(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"tes\[0\]\.inputs\.a0: .*'2.0 volts' not allowed"):
        load_plant(_plant(tmp_path, '{ a0 = "2.0 volts" }'))


def test_python_users_give_a_quantity() -> None:
    tes = Tes("TES 8EA")
    tes.set_input("a0", Quantity(12, "mA"))
    tes.set_input("a1", Quantity(3, "V"))
    tes.advance(1.0)
    assert [tes.peek(0x003), tes.peek(0x004)] == [614, 307]
