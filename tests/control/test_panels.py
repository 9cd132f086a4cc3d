"""GET /dashboard/state's content, computed in-process on simulated time (deterministic):
each kind's decoded fields, the discrete bits, and that looking changes nothing."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from fieldtwin.control.panels import LAST_MESSAGES, panels
from fieldtwin.control.resources import Control
from fieldtwin.plant import Plant, load_plant
from fieldtwin.runtime.runner import Runner
from tests.tsx.dem24.helpers import unread_default_plant


@pytest.fixture(scope="module")
def state(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Plant, Control, Any]]:
    # the default plant without its program's reading of the DEM stack: the stack the
    # page looks at fills (tests/tsx/dem24/test_default_plant_stack.py: the reading)
    plant = load_plant(unread_default_plant(tmp_path_factory.mktemp("panels")), speed=None)
    assert plant.plc is not None
    plant.plc.advance(80.0)
    control = Control(plant, Runner(plant.clock, None), plant.events)
    yield plant, control, panels(control)
    plant.close()


def module(state: Any, ident: str) -> Any:
    return next(m for m in state["modules"] if m["id"] == ident)


def test_the_plc_front_and_every_device(state: tuple[Plant, Control, Any]) -> None:
    _, _, s = state
    assert s["plc"]["model"] == "TSX 87" and s["plc"]["mode"] == "RUN"
    assert s["plc"]["scan_ms"] == 10.0
    assert s["clock"]["t_s"] == pytest.approx(80.0, abs=0.01)
    assert [m["id"] for m in s["modules"]] == ["4", "5", "7", "14", "16", "17"]
    assert [m["leds"] for m in s["modules"] if m["id"] == "7"] == [[["OK", "on"], ["F", "off"]]]


def test_the_aem_channels_in_their_configured_scaling(state: tuple[Plant, Control, Any]) -> None:
    plant, _, s = state
    aem = module(s, "5")
    ch4 = aem["decoded"]["channels"][4]  # 2.5 V on 0/10 V, square root, 0..20000
    assert ch4["value"] == 10000 and ch4["range"] == "0/10 V" and ch4["sqrt"] is True
    assert ch4["threshold_bits"] in ("00", "01", "10", "11")
    ch1 = aem["decoded"]["channels"][1]  # 12 mA on 4/20 mA scaled 0..10000 (the 12-bit converter)
    assert abs(ch1["value"] - 5000) <= 2 and ch1["range"] == "4/20 mA" and ch1["sqrt"] is False
    assert [w["name"] for w in aem["iw"]] == [f"IW5,{i}" for i in range(8)]
    assert plant.plc is not None
    assert aem["iw"][3]["value"] == plant.plc.read("IW5,3")


def test_the_dem_stack_is_looked_at_not_read(state: tuple[Plant, Control, Any]) -> None:
    plant, control, s = state
    dem = module(s, "4")["decoded"]
    assert dem["time"].startswith("1994-07-15") and dem["logging"] == "active"
    assert dem["size"] == 200 and 0 < dem["fill"] <= 200 and dem["overflow"] is False
    stamps = [m["stamp"] for m in dem["messages"]]
    assert len(stamps) == min(LAST_MESSAGES, dem["fill"])
    assert stamps == sorted(stamps, reverse=True)  # newest first
    assert all(m["type"] in ("change", "overall") for m in dem["messages"])
    again = module(panels(control), "4")["decoded"]
    assert again["fill"] == dem["fill"] and again["messages"] == dem["messages"]


def test_discrete_bits_and_the_tes_fronts(state: tuple[Plant, Control, Any]) -> None:
    plant, _, s = state
    assert plant.plc is not None
    det, dst = module(s, "14"), module(s, "16")
    assert det["i_bits"] & 1 == 1 and det["o_bits"] is None
    assert dst["i_bits"] is None
    assert dst["o_bits"] == sum(plant.plc.read(f"O16,{b:X}") << b for b in range(16)) != 0
    tes1 = next(t for t in s["tes"] if t["id"] == "tes1")
    assert len(tes1["inputs"]) == 16 and len(tes1["outputs"]) == 16
    assert tes1["inputs"][2] is True  # the plant file's input 2 = true
    rises = tes1["counters"][0]["rise"]  # a 1 s pulse for 80 s
    assert 79 <= rises <= 81
    assert tes1["watchdog"] == {"word": 0, "seconds": 0.0, "led": "off"}
    tes2 = next(t for t in s["tes"] if t["id"] == "tes2")
    a1 = next(a for a in tes2["analog"] if a["input"] == "a1")
    assert a1 == {"input": "a1", "level": 2.5, "unit": "V", "points": 256, "full_scale": 10.0}
