"""A recording the previous release wrote (fieldtwin 0.1.0, format version 1) replays
identically: the command door changed how commands reach the plant and how the recorder
sees them, not what a recording holds.  A format this fieldtwin does not read is
refused with a message naming the version."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import pytest

from fieldtwin.errors import ConfigError
from fieldtwin.replay import replay
from fieldtwin.runtime.record import read_header, read_recording
from tests.record.runs import fieldtwin

# `fieldtwin run default.toml --record` of fieldtwin 0.1.0 before the door: a Modbus TCP
# poll, control-API calls (set_input, pause, step, write_object, resume) and console
# lines (one advances the clock, one is refused), about 2 simulated seconds
PREVIOUS = Path(__file__).parent / "golden" / "release-0.1.0.ftrec"


def test_the_previous_releases_recording_holds_calls_lines_and_wire_bytes() -> None:
    header, records = read_recording(PREVIOUS)
    assert (header.version, header.fieldtwin, header.console) == (1, "0.1.0", "modes")
    calls = [r[3] for r in records if r[0] == "call"]
    assert calls == ["set_input", "pause", "step", "write_object", "resume"]
    assert [r[3] for r in records if r[0] == "line"][-1] == "no such command"
    assert {"accept", "data", "send", "ret", "result"} <= {r[0] for r in records}


def test_the_previous_releases_recording_replays_identically() -> None:
    outcome = replay(PREVIOUS)
    assert outcome.identical, outcome.difference
    assert outcome.expected == outcome.produced > 1000
    assert outcome.inputs == 49


def test_the_previous_releases_recording_replays_from_the_command_line() -> None:
    done = fieldtwin("replay", str(PREVIOUS))
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.startswith("identical: 49 inputs"), done.stdout


@pytest.mark.parametrize("version", [0, 2])
def test_a_format_version_this_fieldtwin_does_not_read_is_refused_by_name(
    tmp_path: Path, version: int
) -> None:
    with gzip.open(PREVIOUS, "rt", encoding="utf-8") as file:
        header, *rest = file.read().splitlines()
    other = tmp_path / f"v{version}.ftrec"
    with gzip.open(other, "wt", encoding="utf-8") as file:
        file.write("\n".join([json.dumps({**json.loads(header), "version": version}), *rest]))
    message = f"{other}: recording format version {version}; this fieldtwin reads version 1"
    with pytest.raises(ConfigError, match=message):
        read_header(other)
    done = fieldtwin("replay", str(other))
    assert done.returncode == 2 and message in done.stderr, done.stdout + done.stderr
