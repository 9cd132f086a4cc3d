"""Black box: `fieldtwin run --record` of the default plant under a 10 Hz pymodbus poll,
then `fieldtwin replay` (identical; a changed parameter differs readably) and `fieldtwin diff`."""

from __future__ import annotations

import gzip
import json
import time
from pathlib import Path

import pytest

from tests.record.runs import DEFAULT_PLANT, Run, fieldtwin, free_port_plant, start

POLL_HZ = 10
POLL_S = 2.5


def _poll(run: Run, seconds: float) -> int:
    """A SCADA-style master: 10 Hz, holding registers of TES 1, input registers of TES 2."""
    from pymodbus.client import ModbusTcpClient

    client = ModbusTcpClient("127.0.0.1", port=run.tcp[0], timeout=2, retries=0)
    assert client.connect()  # type: ignore[no-untyped-call]
    polls = 0
    try:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            assert not client.read_holding_registers(0, count=2, device_id=1).isError()
            assert not client.read_input_registers(0, count=4, device_id=2).isError()
            if polls % 5 == 0:
                assert not client.write_register(0x100, polls & 0xFF, device_id=1).isError()
            polls += 1
            time.sleep(1 / POLL_HZ)
    finally:
        client.close()  # type: ignore[no-untyped-call]
    return polls


def _control(run: Run) -> None:
    """A control-API input change, console lines (one runs the clock), clock commands."""
    from fieldtwin.control.client import Client

    assert run.control is not None
    with Client(run.control) as client:
        client.set_input("tes2", "a1", 7.25)
        client.console("tes 1 input 3 = true")
        client.console("advance 300ms")
        client.console("no such command")
        client.pause()  # held, stepped while held (its run delivers nothing new), resumed
        client.step(150)
        client.write("tes1", "H'100'", 5)
        client.resume()


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    tmp = tmp_path_factory.mktemp("record")
    plant = free_port_plant(DEFAULT_PLANT, tmp / "default.toml")
    record = tmp / "default.ftrec"
    run = start(plant, record, control=True)
    try:
        polls = _poll(run, POLL_S / 2)
        _control(run)
        polls += _poll(run, POLL_S / 2)
    finally:
        output = run.stop()
    assert polls >= 10, output
    return plant, record


def _records(path: Path) -> list[list[object]]:
    with gzip.open(path, "rt", encoding="utf-8") as file:
        return [json.loads(line) for line in file][1:]


def test_the_recording_holds_the_session(recorded: tuple[Path, Path]) -> None:
    _, record = recorded
    with gzip.open(record, "rt", encoding="utf-8") as file:
        header = json.loads(file.readline())
    assert header["format"] == "fieldtwin-recording" and header["version"] == 1
    assert "TES 8EA" in header["plant"]["text"]
    assert "PROGRAM" in header["plant"]["files"]["default.pl7"].upper()  # the default plant's
    kinds = {r[0] for r in _records(record)}
    assert {"bind", "accept", "data", "send", "call", "line", "ret", "result"} <= kinds
    assert {"object", "led", "end"} <= kinds
    lines = [r[3] for r in _records(record) if r[0] == "line"]
    assert lines == ["tes 1 input 3 = true", "advance 300ms", "no such command"]
    calls = [r[3:] for r in _records(record) if r[0] == "call"]
    assert ["set_input", ["tes2", "a1", 7.25, None]] in calls
    assert [c[0] for c in calls][-4:] == ["pause", "step", "write_object", "resume"]


def test_replay_is_identical(recorded: tuple[Path, Path]) -> None:
    _, record = recorded
    result = fieldtwin("replay", str(record))
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.startswith("identical: ")


def test_a_changed_parameter_fails_with_a_readable_first_difference(
    recorded: tuple[Path, Path],
) -> None:
    plant, record = recorded
    changed = plant.with_name("changed.toml")
    text = plant.read_text("utf-8")
    assert "a1 = 2.5" in text
    changed.write_text(text.replace("a1 = 2.5", "a1 = 2.6"), "utf-8")  # TES 8EA input 1
    result = fieldtwin("replay", str(record), "--plant", str(changed))
    assert result.returncode == 1, result.stdout + result.stderr
    out = result.stdout
    assert out.startswith("different: ")
    assert "first difference at output" in out
    minus = next(line for line in out.splitlines() if line.startswith("  - recorded"))
    plus = next(line for line in out.splitlines() if line.startswith("  + replayed"))
    # the same record of the same device at the same instant, another value
    assert minus.split("=")[:2] == plus.split("=")[:2] or minus.split()[3:6] == plus.split()[3:6]
    assert minus != plus


def test_diff_of_a_recording_with_itself_and_with_another(
    recorded: tuple[Path, Path], tmp_path: Path
) -> None:
    plant, record = recorded
    same = fieldtwin("diff", str(record), str(record))
    assert same.returncode == 0, same.stdout + same.stderr
    assert same.stdout.startswith("identical")
    other = tmp_path / "other.ftrec"
    run = start(plant, other)
    time.sleep(0.5)
    run.stop()
    different = fieldtwin("diff", str(record), str(other))
    assert different.returncode == 1, different.stdout + different.stderr
    assert "first difference" in different.stdout


def test_not_a_recording_is_named(tmp_path: Path) -> None:
    bogus = tmp_path / "bogus.ftrec"
    bogus.write_text("hello")
    result = fieldtwin("replay", str(bogus))
    assert result.returncode == 2
    assert str(bogus) in result.stderr
