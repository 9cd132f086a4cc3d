"""examples/aem811.toml loads, configures the module after its self-test and runs live."""

from __future__ import annotations

from pathlib import Path

from fieldtwin.plant import load_plant

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "aem811.toml"


def test_example_plant_is_live() -> None:
    plant = load_plant(EXAMPLE)
    plc = plant.plc
    assert plc is not None
    plc.advance(10.1)
    assert plc.read("IW5,2,D") == 0 and plc.read("IW5,0,B") == 0  # configured
    plc.write("OW5,0,C", 1)
    plc.advance(6.5)
    mod = plc.module(0, 5)
    assert abs(mod.values[1] - 5000) <= 3  # 12 mA -> 5000 mm
    assert abs(mod.values[6] - 16000) <= 3  # 6.4 V -> 16 l/min
    assert plc.read("I5,6") == 1 and plc.read("I5,4") == 0  # flow alarm on tank 2 only
    r = plc.exchange(m=0x0500, c=3, recv_bytes=16)
    assert r.words == [1000] * 4 + [15000] * 4
