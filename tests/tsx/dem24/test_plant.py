"""The example plant file and the DEM keys of a ``[[module]]`` table."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.plant import _parse, build_plant, load_plant
from fieldtwin.tsx import registry
from fieldtwin.tsx.dem24 import Dem2412, Dem2413
from tests.tsx.dem24.helpers import read_all, stamp

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "dem24.toml"


def test_registry_knows_both_modules() -> None:
    assert registry.module_class("TSX DEM 2412") is Dem2412
    assert registry.module_class("tsx dem 2413") is Dem2413


def test_example_plant_logs_its_live_inputs() -> None:
    plant = load_plant(EXAMPLE)
    plc = plant.plc
    assert plc is not None
    mod = plc.module(0, 4)
    plc.write("OW4,2", 0x0007)
    plc.write("OW4,0,C", 1)
    plc.advance(100.0)  # self-test 10 s; pulses at 30 s (period), 60 s (time taken)
    assert plc.read("I4,0") == 1 and plc.read("IW4,2,D") == 0
    assert plc.read("IW4,6,3") == 1  # 24 V on channel 3
    msgs = read_all(plc)
    assert (msgs[0][1] >> 10) & 1 == 1
    assert stamp(msgs[0]) == (94, 7, 15, 18, 6, 30, 0)
    channels = {m[7] >> 8 for m in msgs[1:] if not (m[1] >> 10) & 1}
    assert channels == {0, 1, 2}
    edge_75 = [m for m in msgs if m[7] >> 8 == 2]
    assert stamp(edge_75[0]) == (94, 7, 15, 18, 6, 45, 0)  # 75 s: 15 s after the 60 s pulse
    assert mod.timebase.clock.drift_ppm == 12.0


def _plant(text: str) -> object:
    return build_plant(_parse(text, "p.toml", Path(".")))


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ('colour = "red"', "module[0].colour"),
        ('time = "1994-13-15T18:05:33"', "module[0].time"),
        ("sync = { period_s = -1 }", "module[0].sync"),
        ("config = [0, 15, 0, 0, 0, 0, 60, 2, 0]", "FILT 15"),
        ("inputs = { 24 = true }", "module[0].inputs.24"),
        ('faults = ["smoke"]', "unknown fault 'smoke'"),
    ],
)
def test_plant_keys_errors_name_the_field(extra: str, message: str) -> None:
    text = f'[[module]]\ntype = "TSX DEM 2412"\nslot = 4\n{extra}\n'
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        _plant(text)


def test_plant_wires_a_sync_output() -> None:
    text = (
        '[[module]]\ntype = "TSX DEM 2412"\nslot = 5\nsync = { from_slot = 4 }\n'
        '[[module]]\ntype = "TSX DEM 2413"\nslot = 4\nsync = { period_s = 1 }\n'
    )
    plant = build_plant(_parse(text, "p.toml", Path(".")))
    plc = plant.plc
    assert plc is not None
    plc.advance(12.01)
    assert plc.module(0, 4).pulse_image == plc.module(0, 5).pulse_image
    assert plc.module(0, 5).timebase.pulses == 3  # at 10, 11 and 12 s (self-test ends at 10)
