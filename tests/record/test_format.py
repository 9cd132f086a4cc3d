"""The recording file, the Python API (plant.record), and how differences are shown."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import pytest

from fieldtwin.clock import SimClock
from fieldtwin.console import Console
from fieldtwin.errors import ConfigError
from fieldtwin.plant import build_plant, load_plant, read_plant, recording_header
from fieldtwin.replay import diff, replay
from fieldtwin.runtime.events import EventBus
from fieldtwin.runtime.record import Recorder, read_recording
from fieldtwin.runtime.replay import compare
from fieldtwin.runtime.runner import Runner
from fieldtwin.transports.memory import memory_pair

AEM_PLANT = """
[plant]
name = "aem only"

[[module]]
type = "TSX AEM 811"
rack = 0
slot = 5
inputs = [
  { channel = 0, milliamps = { kind = "sine", offset = 12.0, amplitude = 6.0, period_s = 2 } },
]

[[tes]]
model = "TES 8EA"
slave = 2
endpoint = "tcp://127.0.0.1:0"
inputs = { a0 = { kind = "sine", offset = 5.0, amplitude = 4.0, period_s = 3 }, a1 = 2.5 }
"""


def _aem_plant(tmp_path: Path) -> Path:
    path = tmp_path / "aem.toml"
    path.write_text(AEM_PLANT, "utf-8")
    return path


def _session(tmp_path: Path, value: str = "12mA") -> Path:
    plant = load_plant(_aem_plant(tmp_path))
    record = tmp_path / f"aem-{value}.ftrec"
    plant.record(record)
    console = Console(plant)
    console.execute("OW5,0,C = 1")
    console.execute("advance 3")
    console.execute(f"input 5 1 {value}")
    console.execute("advance 1")
    with pytest.raises(ConfigError):
        console.execute("no such command")
    plant.close()
    return record


def test_a_python_session_through_the_console_replays_identically(tmp_path: Path) -> None:
    record = _session(tmp_path)
    header, records = read_recording(record)
    assert header.plant_name == str(tmp_path / "aem.toml") and "AEM 811" in header.plant_text
    lines = [r[3] for r in records if r[0] == "line"]
    assert lines == ["OW5,0,C = 1", "advance 3", "input 5 1 12mA", "advance 1", "no such command"]
    errors = [r[3] for r in records if r[0] == "result" and isinstance(r[3], dict)]
    assert errors and "unknown command" in str(errors[0]["error"])
    outcome = replay(record)
    assert outcome.identical, outcome.difference
    assert outcome.sim_us == 4_000_000


def test_another_input_value_differs_and_diff_says_where(tmp_path: Path) -> None:
    a, b = _session(tmp_path), _session(tmp_path, "16mA")
    text = diff(a, b)
    assert text is not None
    assert text.startswith("inputs: first difference at input 6")  # bind, line, ret, line, ret
    assert "console 'input 5 1 16mA'  (after " in text and "outputs: first difference" in text
    assert diff(a, a) is None


def test_the_replay_of_a_changed_plant_shows_the_first_difference_in_context(
    tmp_path: Path,
) -> None:
    record = _session(tmp_path)
    changed = tmp_path / "changed.toml"
    changed.write_text(AEM_PLANT.replace("a1 = 2.5", "a1 = 2.6"), "utf-8")
    outcome = replay(record, changed)
    assert not outcome.identical and outcome.difference is not None
    lines = outcome.difference.splitlines()
    assert lines[0].startswith("first difference at output ")
    assert any(line.startswith("    same ") for line in lines)
    minus = next(line for line in lines if line.startswith("  - recorded"))
    plus = next(line for line in lines if line.startswith("  + replayed"))
    # the TES 8EA's input 1 word (H'004'), at the same instant, another value
    assert "object tcp://127.0.0.1:0 2 H'004' = " in minus
    assert minus.split(" = ")[0].replace("- recorded", "") == plus.split(" = ")[0].replace(
        "+ replayed", ""
    )
    assert minus != plus


def test_recording_starts_before_the_plant_runs_and_only_once(tmp_path: Path) -> None:
    plant = load_plant(_aem_plant(tmp_path))
    plant.record(tmp_path / "a.ftrec")
    with pytest.raises(ConfigError, match="already recording"):
        plant.record(tmp_path / "b.ftrec")
    plant.close()
    ran = load_plant(_aem_plant(tmp_path))
    assert ran.plc is not None
    ran.plc.advance(0.5)
    with pytest.raises(ConfigError, match="before the plant runs"):
        ran.record(tmp_path / "c.ftrec")


def test_a_transport_attached_again_is_recorded_once_under_its_new_name(tmp_path: Path) -> None:
    clock = SimClock()
    runner = Runner(clock, speed=None)
    plant = build_plant(read_plant(_aem_plant(tmp_path)), runner=runner, speed=None)
    ours, theirs = memory_pair()
    runner.attach(ours, lambda data, now: None)  # attached before the recording: wrapped by it
    header = recording_header(read_plant(_aem_plant(tmp_path)), None)
    recorder = Recorder(tmp_path / "m.ftrec", header, clock, plant.devices, EventBus(), runner)
    runner.attach(ours, lambda data, now: None)
    ours.send(b"\x01\x02")
    theirs.send(b"\x03")
    runner.advance(1000)
    recorder.close()
    _, records = read_recording(tmp_path / "m.ftrec")
    assert [r for r in records if r[0] == "send"] == [["send", 0, "t2", "0102"]]
    assert [r[3:] for r in records if r[0] == "data"] == [["t2", "03"]]
    assert theirs.receive() == b"\x01\x02"


def _write(path: Path, lines: list[str]) -> None:
    with gzip.open(path, "wt", encoding="utf-8") as file:
        file.write("\n".join(lines) + "\n")


def test_what_is_not_a_recording_is_named(tmp_path: Path) -> None:
    plain = tmp_path / "plain.ftrec"
    plain.write_text("not gzip")
    with pytest.raises(ConfigError, match=f"{plain}: cannot read the recording"):
        read_recording(plain)
    other = tmp_path / "other.ftrec"
    _write(other, [json.dumps({"format": "something else"})])
    with pytest.raises(ConfigError, match="not a fieldtwin recording"):
        read_recording(other)
    header = json.loads(
        json.dumps(recording_header(read_plant(_aem_plant(tmp_path)), 1.0).as_json())
    )
    future = tmp_path / "future.ftrec"
    _write(future, [json.dumps({**header, "version": 99})])
    with pytest.raises(ConfigError, match="format version 99; this fieldtwin reads version 1"):
        read_recording(future)
    damaged = tmp_path / "damaged.ftrec"
    _write(damaged, [json.dumps(header), '["data", 0, 0, "t1", "00"]', "{oops"])
    with pytest.raises(ConfigError, match="line 3: not JSON"):
        read_recording(damaged)
    unknown = tmp_path / "unknown.ftrec"
    _write(unknown, [json.dumps(header), '["teleport", 0]'])
    with pytest.raises(ConfigError, match="line 2: unknown record 'teleport'"):
        read_recording(unknown)


def test_a_shorter_stream_is_a_difference() -> None:
    a = [["send", 1000, "t1", "0102"], ["led", 2000, "5", "ERR", "on"]]
    assert compare(a, a) is None
    found = compare(a, a[:1])
    assert found is not None and found.index == 1
    assert "(nothing: the stream has ended)" in found.text
    assert "t = 0.001000 s  send t1  01 02" in found.text


def test_a_damaged_stream_is_named_not_a_traceback(tmp_path: Path) -> None:
    record = _session(tmp_path)
    data = bytearray(record.read_bytes())
    middle = len(data) // 2
    data[middle : middle + 64] = bytes(64)  # zeroes inside the deflate stream
    record.write_bytes(bytes(data))
    with pytest.raises(ConfigError, match=f"{record}: (cannot read the recording|line )"):
        replay(record)


def test_the_streamed_comparison_counts_every_record_and_keeps_only_the_context() -> None:
    expected = [["send", t, "t1", "00"] for t in range(1000)]
    actual = [*expected[:500], ["send", 500, "t1", "ff"], *expected[501:]]
    found = compare(expected, actual)
    assert found is not None and found.index == 500
    assert found.text.startswith("first difference at output 501 (of 1000 recorded):")
    assert found.text.count("same ") == 3  # the context before it, not the 500
    assert "- recorded t = 0.000500 s  send t1  00" in found.text
    assert "+ replayed t = 0.000500 s  send t1  ff" in found.text


def test_dem_messages_are_recorded_and_replayed(tmp_path: Path) -> None:
    plant = load_plant(None, speed=None)  # the default plant: its DEM logs from t = 60 s on
    record = tmp_path / "dem.ftrec"
    plant.record(record)
    Console(plant).execute("advance 70")
    plant.close()
    _, records = read_recording(record)
    dem = [r for r in records if r[0] == "dem"]
    assert dem and all(r[2] == "4" and r[3].startswith("1994-07-15 18:06:") for r in dem)
    assert {r[4] for r in dem} <= {"change", "overall"}
    outcome = replay(record)
    assert outcome.identical, outcome.difference
