"""Tags in a plant file (docs/plant.md, "Tags"): read by name, scaled into their unit,
and every mistake named by its plant-file field with what is allowed."""

from __future__ import annotations

from pathlib import Path

import pytest

from fieldtwin.control.observer import Observer
from fieldtwin.errors import ConfigError
from fieldtwin.plant import load_plant
from fieldtwin.plant.tags import UnknownTag, read_value, resolve, tag_value
from fieldtwin.runtime.events import EventBus

PLANT = """
[plc]
model = "TSX 87"
[[module]]
type = "TSX AEM 811"
slot = 5
inputs = { 0 = "12mA", 4 = "5V" }
[[module]]
type = "TSX DET 805"
rack = 1
slot = 4
inputs = { 0 = 1 }
[[module]]
type = "TSX DST 1635"
rack = 1
slot = 6
[[tes]]
model = "TES 8EA"
slave = 2
endpoint = "tcp://127.0.0.1:5020"
inputs = { a0 = 5.0 }
"""

TAGS = """
[dashboard]
trends = ["level", "W4"]
[[tag]]
name = "level"
object = "W0"
unit = "mm"
scale = [0, 10000, 0, 10]
description = "tank level"
[[tag]]
name = "lamp"
object = "o16,3"
[[tag]]
name = "channel0"
device = "5"
input = "0"
[[tag]]
name = "switch"
device = "14"
input = 0
[[tag]]
name = "pressure"
device = "tes2"
input = "a0"
unit = "bar"
scale = [0, 10, 0, 6]
[[tag]]
name = "watchdog"
device = "tes2"
register = "watchdog"
"""


def plant_with(tmp_path: Path, tags: str) -> Path:
    path = tmp_path / "plant.toml"
    path.write_text(PLANT + tags)
    return path


def test_tags_read_their_source_scaled_into_their_unit(tmp_path: Path) -> None:
    plant = load_plant(plant_with(tmp_path, TAGS))
    try:
        assert [t.name for t in plant.tags] == [
            "level",
            "lamp",
            "channel0",
            "switch",
            "pressure",
            "watchdog",
        ]
        assert plant.tags.trends == ("level", "W4")
        assert plant.plc is not None
        plant.plc.write("W0", 2500)
        level = read_value(plant, "LEVEL")  # names are case-insensitive
        assert (level.value, level.raw, level.unit, level.text) == (2.5, 2500, "mm", "2.5 mm")
        plant.plc.write("O16,3", 1)
        lamp = read_value(plant, "lamp")
        assert lamp.value is True and lamp.text == "on"
        assert plant.tags.named("lamp").source.name == "O16,3"  # written as the console does
        pressure = read_value(plant, "pressure")
        assert pressure.raw == pytest.approx(5.0, abs=0.01)
        assert pressure.value == pytest.approx(3.0, abs=0.01) and pressure.unit == "bar"
        assert isinstance(read_value(plant, "watchdog").value, int)
        assert plant.tags.named("watchdog").source.text.startswith("tes2 register H'")
        # the AEM's channel, its own measurement once measured (not a multiplexed IW5,3)
        plant.clock.advance(3_000_000)
        assert read_value(plant, "switch").value is True  # I14,0 of the DET 805, scanned
        assert isinstance(read_value(plant, "channel0").value, int)
        # an object without a tag resolves as one of its own name; a tagged one to its tag
        assert resolve(plant, "w4").name == "W4"
        assert resolve(plant, "W0").name == "level"
        assert tag_value(plant, resolve(plant, "W0")).value == 2.5
        with pytest.raises(UnknownTag, match=r"no tag 'nope' \(allowed: level, lamp"):
            resolve(plant, "nope")
    finally:
        plant.close()


def test_a_plant_without_tags_has_none(tmp_path: Path) -> None:
    plant = load_plant(plant_with(tmp_path, ""))
    try:
        assert not plant.tags and plant.tags.trends == ()
        with pytest.raises(ConfigError, match="this plant file has no \\[\\[tag\\]\\] table"):
            plant.tags.named("x")
    finally:
        plant.close()


@pytest.mark.parametrize(
    ("tags", "message"),
    [
        (
            '[[tag]]\nname = "a"\nobject = "W0"\n[[tag]]\nname = "A"\nobject = "W1"',
            "plant.toml: tag[1].name: 'A' is already the name of tag[0]",
        ),
        ('[[tag]]\nname = "a"\nobject = "Q9"', "plant.toml: tag[0].object: "),
        (
            '[[tag]]\nname = "a"\ndevice = "tes9"\ninput = "0"',
            "plant.toml: tag[0].device: 'tes9' not allowed (allowed: 5, 14, 16, tes2)",
        ),
        (
            '[[tag]]\nname = "a"\ndevice = "tes2"\ninput = "7"',
            "plant.toml: tag[0].input: '7' is no input of TES 8EA tes2 (allowed: 0..3, a0..a7)",
        ),
        (
            '[[tag]]\nname = "a"\ndevice = "tes2"\nregister = "H\'FFF\'"',
            "plant.toml: tag[0].register: \"H'FFF'\" is no register of TES 8EA tes2",
        ),
        (
            '[[tag]]\nname = "a"\ndevice = "tes2"\noutput = "9"',
            "plant.toml: tag[0].output: '9' is no output of TES 8EA tes2",
        ),
        (
            '[[tag]]\nname = "a"\ndevice = "tes2"\ninput = "a0"\nregister = "1"',
            "plant.toml: tag[0]: device tes2 takes one of input, output or register"
            " (input and register given; allowed: exactly one)",
        ),
        (
            '[[tag]]\nname = "a"\nobject = "W0"\ndevice = "tes2"',
            "plant.toml: tag[0]: give either object",
        ),
        ('[[tag]]\nname = "a"', "not neither"),
        (
            '[[tag]]\nname = "a"\nobject = "W0"\nscale = [0, 0, 1, 2]',
            "plant.toml: tag[0].scale: raw_lo and raw_hi are both 0"
            " (allowed: two different values)",
        ),
        (
            '[[tag]]\nname = "a"\nobject = "W0"\nscale = [0, 10, 5, 5]',
            "plant.toml: tag[0].scale: eng_lo and eng_hi are both 5"
            " (allowed: two different values)",
        ),
        (
            '[[tag]]\nname = "a"\nobject = "W0"\nscale = { factor = 2 }',
            "plant.toml: tag[0].scale: {'factor': 2} not allowed (allowed: four numbers"
            " [raw_lo, raw_hi, eng_lo, eng_hi]",
        ),
        (
            '[[tag]]\nname = "a"\nobject = "O16,0"\nscale = [0, 1, 0, 2]',
            "plant.toml: tag[0].scale: O16,0 is a bit (on/off)",
        ),
        ('[[tag]]\nname = "W12"\nobject = "W0"', "plant.toml: tag[0].name: 'W12' reads as a PL7"),
        ('[[tag]]\nname = "tes2"\nobject = "W0"', "plant.toml: tag[0].name: 'tes2' is a device's"),
        ('[[tag]]\nname = "a b"\nobject = "W0"', "plant.toml: tag[0].name: 'a b' not allowed"),
        ('[[tag]]\nobject = "W0"', "plant.toml: tag[0].name: missing or not a string"),
        (
            '[[tag]]\nname = "a"\nobject = "W0"\ncolour = "red"',
            "plant.toml: tag[0]: unknown key(s) colour (allowed: name, unit, scale",
        ),
        ('[[tag]]\nname = "a"\nobject = "W0"\nunit = 3', "plant.toml: tag[0].unit: 3 not allowed"),
        (
            '[dashboard]\ntrends = ["nope"]',
            "plant.toml: dashboard.trends[0]: 'nope' is no tag of this plant nor a PL7 object",
        ),
        (
            "[dashboard]\nlayout = 1",
            "plant.toml: dashboard: unknown key(s) layout (allowed: trends)",
        ),
    ],
)
def test_a_mistake_in_a_tag_names_its_field(tmp_path: Path, tags: str, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        load_plant(plant_with(tmp_path, tags))
    assert message in str(info.value)
    assert "allowed" in str(info.value) or "give either" in str(info.value)


def test_the_default_plant_tells_its_story() -> None:
    plant = load_plant(None)
    try:
        names = [t.name for t in plant.tags]
        assert plant.tags.trends == ("tank0.level", "tank1.level", "tank2.level", "tank3.level")
        for name in ("tank1.flow", "plant.run", "line.part_present", "scm.rx_count", "pump1.run"):
            assert name in names
        plant.clock.advance(20_000_000)
        flow = read_value(plant, "tank1.flow")  # W5: 16000 thousandths of l/min
        assert flow.unit == "l/min" and flow.value == pytest.approx(16.0, abs=0.1)
        level = read_value(plant, "tank0.level")
        assert level.unit == "mm" and 500 <= level.value <= 8500  # type: ignore[operator]
        assert level.value == read_value(plant, "tank0.level.channel").value
    finally:
        plant.close()


def test_the_wide_live_view_names_the_tags_in_their_units() -> None:
    from rich.console import Console

    from fieldtwin.live import render, tags_lines

    plant = load_plant(None)
    try:
        plant.clock.advance(20_000_000)
        line = tags_lines(plant)[0].plain
        assert line.startswith("tags: tank0.level ") and " mm  tank1.level " in line
        assert "tank1.flow 16 l/min" in line and line.endswith("(+1)")  # 24 of 25 named
        wide = Console(width=160, height=80, record=True)
        wide.print(render(plant, []))
        assert "tags: tank0.level" in wide.export_text()
        narrow = Console(width=80, height=24, record=True)  # the default plant fits 80 x 24
        narrow.print(render(plant, []))
        assert "tags:" not in narrow.export_text()
    finally:
        plant.close()


def test_a_trend_ring_is_bounded_and_sampled_at_most_every_period(tmp_path: Path) -> None:
    from fieldtwin.control.trends import MAX_SERIES, TooManySeries, Trends

    plant = load_plant(plant_with(tmp_path, TAGS))
    try:
        assert plant.plc is not None
        trends = Trends(plant, sample_us=500_000, max_points=3)
        assert trends.names() == [
            "level",
            "lamp",
            "channel0",
            "switch",
            "pressure",
            "watchdog",
            "W4",
        ]
        level = plant.tags.named("level")
        for step, word in enumerate((1000, 2000, 3000, 4000, 5000)):
            plant.plc.write("W0", word)
            trends.sample(step * 500_000)
            trends.sample(step * 500_000 + 100_000)  # within the period: not sampled
        assert trends.points(level) == [(1.0, 3.0), (1.5, 4.0), (2.0, 5.0)]  # the last 3
        assert trends.points(level, since_s=1.5) == [(2.0, 5.0)]
        assert trends.track("w4").name == "W4" and "W4" in trends.names()
        assert trends.tag("W0") is level  # an object by its tag's source
        for k in range(MAX_SERIES - 1):
            trends.track(f"W{100 + k}")
        with pytest.raises(TooManySeries, match=f"{MAX_SERIES} series are kept"):
            trends.track("W999")
        with pytest.raises(UnknownTag):
            trends.track("nope")
    finally:
        plant.close()


def test_an_object_event_carries_the_tag_beside_the_object(tmp_path: Path) -> None:
    plant = load_plant(
        plant_with(tmp_path, TAGS + '[[tag]]\nname = "aem.out0"\nobject = "OW5,0"\n')
    )
    try:
        bus = EventBus()
        sub = bus.subscribe(["object"])
        observer = Observer(plant.devices, bus, plant.tags)
        observer.sample(0)  # the first look publishes nothing
        tes = next(d for d in plant.devices if str(d.address).endswith(" 2"))
        register = plant.tags.named("watchdog").source.name
        tes.objects().write(register, tes.objects().peek(register) ^ 1)
        aem = next(d for d in plant.devices if str(d.address) == "5")
        aem.objects().write("OW5,0", aem.objects().peek("OW5,0") ^ 1)
        aem.objects().write("OW5,1", aem.objects().peek("OW5,1") ^ 1)
        observer.sample(1)
        got = {e.data["object"]: e.data.get("tag") for e in sub.take()}
        assert got[register] == "watchdog" and got["OW5,0"] == "aem.out0"
        assert "OW5,1" in got and got["OW5,1"] is None  # no tag: none in the event
    finally:
        plant.close()
