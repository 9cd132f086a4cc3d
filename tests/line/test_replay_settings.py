"""Issue 23: a recording keeps the master's line settings on a pty (``settings`` inputs),
so that `fieldtwin replay` reproduces a mismatch: a real `fieldtwin run --record`, a
pyserial master at the right speed, at 9600 Bd against the TES's 38400, right again."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import pytest
import serial

from fieldtwin.modbus.crc import with_crc
from tests.record.runs import fieldtwin, start

PLANT = Path(__file__).parent / "plants" / "tes_pty.toml"
READ_INPUTS = with_crc(bytes([1, 0x03, 0x00, 0x05, 0x00, 0x01]))  # word 005h: input 2 on
READ_WRONG_CHARACTERS = with_crc(bytes([1, 0x03, 0x00, 0x1B, 0x00, 0x01]))  # 01Bh
ANSWER = with_crc(bytes([1, 0x03, 0x02, 0x00, 0x04]))
WAIT_S = 0.5  # "no answer": far beyond a 38400 Bd exchange
ANSWER_S = 3.0  # the bound on an answer


def _exchange(path: str, request: bytes, baud: int, wait: float = ANSWER_S) -> bytes:
    with serial.Serial(path, baud, parity="E", timeout=wait) as port:
        port.write(request)
        return bytes(port.read(7))


def _records(path: Path) -> list[list[object]]:
    with gzip.open(path, "rt", encoding="utf-8") as file:
        return [json.loads(line) for line in file][1:]


def _rewrite(source: Path, target: Path, keep: object) -> None:
    with gzip.open(source, "rt", encoding="utf-8") as file:
        lines = file.readlines()
    kept = [lines[0], *(x for x in lines[1:] if keep(json.loads(x)))]  # type: ignore[operator]
    with gzip.open(target, "wt", encoding="utf-8") as file:
        file.writelines(kept)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    record = tmp_path_factory.mktemp("line") / "wrong_baud.ftrec"
    run = start(PLANT, record)
    try:
        (path,) = run.rtu_ptys
        assert _exchange(path, READ_INPUTS, 38400) == ANSWER
        assert _exchange(path, READ_INPUTS, 9600, WAIT_S) == b""  # the TES read garbage
        reply = _exchange(path, READ_WRONG_CHARACTERS, 38400)
        assert reply[:3] == bytes([1, 3, 2]) and int.from_bytes(reply[3:5], "big") >= 8
    finally:
        output = run.stop()
    assert "line settings differ: master 9600 8E1, TES 38400 8E1" in output
    return record


def test_the_recording_keeps_the_masters_settings(recorded: Path) -> None:
    records = _records(recorded)
    settings = [r[3:] for r in records if r[0] == "settings"]
    assert settings == [["t1", 38400, 1, False], ["t1", 9600, 1, False], ["t1", 38400, 1, False]]
    # each change comes before the bytes the master sent with it
    kinds = [r[0] for r in records if r[0] in ("settings", "data")]
    assert kinds[0] == "settings" and kinds.index("data") > 0
    sends = [r for r in records if r[0] == "send"]
    assert len(sends) == 2  # the answer at 38400 and the counter; none at 9600


def test_replay_reproduces_the_mismatch(recorded: Path) -> None:
    result = fieldtwin("replay", str(recorded))
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.startswith("identical: ")


def test_without_the_settings_the_replay_differs(recorded: Path, tmp_path: Path) -> None:
    """A recording made before the ``settings`` input (none in it) still replays; of this
    session, the TES then answers the 9600 Bd request, and the replay says so."""
    older = tmp_path / "older.ftrec"
    _rewrite(recorded, older, lambda record: record[0] != "settings")
    result = fieldtwin("replay", str(older))
    assert result.returncode == 1, result.stdout + result.stderr
    assert result.stdout.startswith("different: ")
    assert "first difference at output" in result.stdout


def test_a_damaged_settings_record_is_named(recorded: Path, tmp_path: Path) -> None:
    damaged = tmp_path / "damaged.ftrec"
    with gzip.open(recorded, "rt", encoding="utf-8") as file:
        lines = file.readlines()
    for number, line in enumerate(lines):
        if line.startswith('["settings"'):
            record = json.loads(line)
            record[5] = 3
            lines[number] = json.dumps(record) + "\n"
            break
    with gzip.open(damaged, "wt", encoding="utf-8") as file:
        file.writelines(lines)
    result = fieldtwin("replay", str(damaged))
    assert result.returncode == 2, result.stdout + result.stderr
    assert f"line {number + 1}: a 'settings' record's stop_bits 3 is not 1 or 2" in result.stderr
